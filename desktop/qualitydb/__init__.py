"""The calibration quality database behind `python -m host_sim quality` (CPython only).

  records  one calibration record: validation of a JSON line, the stored row, the parameters
  store    the database (SQLite file or PostgreSQL server, one schema, one set of statements)
  limits   limits: a user's limits file, or limits learned from device history and the fleet
  trend    per-parameter mean, sigma and drift per month
  fleet    a simulated fleet of devices with known changes (tests and `make bench`)
  chart    the parameter history chart (matplotlib, imported only there)
"""
