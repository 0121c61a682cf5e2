"""The database: an SQLite file or a PostgreSQL server, with one schema and one set of
statements (both through DB-API; only the placeholder style and the way a write transaction
starts differ).

One table, `calibration`, one row per stored calibration (records.COLUMNS); the primary key
(device, time, digest) makes a duplicate impossible even if two ingests race. Every write
runs in one transaction: a batch is stored whole or not at all.
"""
import os
import sqlite3

from desktop.qualitydb import records

SCHEMA_VERSION = 1
SELECT_DEVICES = 500 # devices per look-up of stored records
INSERT_ROWS = 40     # 40 rows x 20 columns = 800 placeholders: below SQLite's old limit of 999
TABLE = "calibration"


class DuplicateError(Exception):
    """A batch holds records that are already stored (or twice in the batch); .rows are
    those records. Nothing of the batch was stored."""

    def __init__(self, rows):
        Exception.__init__(self, "%d duplicate records" % len(rows))
        self.rows = rows


class StoreError(Exception):
    """The database cannot be opened, read or written (locked, read-only, missing, refused);
    the message names the database. Nothing was changed."""


def schema_statements():
    cols = ",\n  ".join("%s %s" % c for c in records.COLUMNS)
    return ["CREATE TABLE IF NOT EXISTS %s (\n  %s,\n  PRIMARY KEY (device, time, digest))"
            % (TABLE, cols),
            "CREATE INDEX IF NOT EXISTS %s_device_t ON %s (device, t_epoch)" % (TABLE, TABLE),
            "CREATE TABLE IF NOT EXISTS quality_schema (version INTEGER NOT NULL)"]


def is_postgres(url):
    return url.startswith("postgresql://") or url.startswith("postgres://")


def describe(url):
    """The database named in messages (a PostgreSQL URL without its password)."""
    if is_postgres(url):
        import urllib.parse
        u = urllib.parse.urlsplit(url)
        host = u.hostname or ""
        netloc = (u.username + "@" if u.username else "") + host + (
            ":%d" % u.port if u.port else "")
        return urllib.parse.urlunsplit((u.scheme, netloc, u.path, u.query, ""))
    return url


class Store:
    """open(url, write=...) -> Store. Methods: add(rows) (one transaction), existing(device),
    rows(), close(). `wait` is how long to wait for another writer's lock, in seconds."""

    def __init__(self, url, write=False, wait=2.0):
        self.url = url
        self.name = describe(url)
        self.pg = is_postgres(url)
        if self.pg:
            self.conn = _pg_connect(url, wait)
        else:
            self.conn = _sqlite_connect(url, write, wait)
        self._error_types = _error_types(self.pg)
        if write:
            self._run(self._create)

    # --- statements -------------------------------------------------------------------
    def _sql(self, text):
        # sqlite3 uses qmark placeholders, pg8000 the format style
        return text.replace("?", "%s") if self.pg else text

    def _run(self, fn, *args):
        """fn(cursor, *args) inside one transaction; any error rolls everything back."""
        cur = self.conn.cursor()
        try:
            if not self.pg:
                cur.execute("BEGIN IMMEDIATE")   # take the write lock before the first row
            out = fn(cur, *args)
            self.conn.commit()
            return out
        except self._error_types as e:
            _rollback(self.conn)
            raise StoreError(self._explain(e))
        except BaseException:
            _rollback(self.conn)
            raise
        finally:
            cur.close()

    def _create(self, cur):
        for s in schema_statements():
            cur.execute(s)
        cur.execute("SELECT version FROM quality_schema")
        got = cur.fetchall()
        if not got:
            cur.execute(self._sql("INSERT INTO quality_schema (version) VALUES (?)"),
                        (SCHEMA_VERSION,))
        elif got[0][0] != SCHEMA_VERSION:
            raise StoreError("%s: schema version %s, this program writes version %d"
                             % (self.name, got[0][0], SCHEMA_VERSION))

    def _explain(self, e):
        text = str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__
        low = text.lower()
        if "locked" in low or "busy" in low:
            return ("%s: database is locked by another writer (waited --wait seconds); "
                    "nothing was changed" % self.name)
        if "readonly" in low or "read-only" in low:
            return "%s: database is read-only; nothing was changed" % self.name
        if "unique" in low or "duplicate key" in low or "23505" in low:
            return ("%s: a record is already stored (another ingest at the same time?); "
                    "nothing was stored" % self.name)
        return "%s: %s" % (self.name, text)

    def ingest(self, rows, skip_duplicates=False):
        """Store the rows that are new, in one transaction: (stored, duplicates) where
        duplicates are the rows already stored or repeated in the batch. With duplicates and
        not skip_duplicates, DuplicateError is raised and nothing is stored."""
        names = records.COLUMN_NAMES
        one = "(%s)" % ", ".join("?" * len(names))

        def ins(n):
            return self._sql("INSERT INTO %s (%s) VALUES %s"
                             % (TABLE, ", ".join(names), ", ".join([one] * n)))

        def sel(n):
            return self._sql("SELECT device, time, digest FROM %s WHERE device IN (%s)"
                             % (TABLE, ", ".join("?" * n)))

        def run(cur):
            seen = set()
            devices = sorted({r["device"] for r in rows})
            for i in range(0, len(devices), SELECT_DEVICES):
                chunk = devices[i:i + SELECT_DEVICES]
                cur.execute(sel(len(chunk)), chunk)
                seen.update(tuple(r) for r in cur.fetchall())
            new, dups = [], []
            for r in rows:
                key = (r["device"], r["time"], r["digest"])
                if key in seen:
                    dups.append(r)
                else:
                    seen.add(key)
                    new.append(r)
            if dups and not skip_duplicates:
                raise DuplicateError(dups)
            # INSERT_ROWS rows per statement: one round trip each on a server
            for i in range(0, len(new), INSERT_ROWS):
                chunk = new[i:i + INSERT_ROWS]
                cur.execute(ins(len(chunk)), [r[c] for r in chunk for c in names])
            return new, dups
        return self._run(run)

    def rows(self, device=None):
        """All stored rows as dicts, by device then time."""
        names = records.COLUMN_NAMES

        def q(cur):
            s = "SELECT %s FROM %s" % (", ".join(names), TABLE)
            args = ()
            if device is not None:
                s += " WHERE device = ?"
                args = (device,)
            cur.execute(self._sql(s + " ORDER BY device, t_epoch, digest"), args)
            return [dict(zip(names, r)) for r in cur.fetchall()]
        return self._read(q)

    def _read(self, fn):
        cur = self.conn.cursor()
        try:
            out = fn(cur)
            if self.pg:
                self.conn.commit()       # end the implicit read transaction
            return out
        except self._error_types as e:
            _rollback(self.conn)
            raise StoreError(self._explain(e))
        finally:
            cur.close()

    def close(self):
        try:
            self.conn.close()
        except Exception:
            pass


def _rollback(conn):
    try:
        conn.rollback()
    except Exception:
        pass


def _error_types(pg):
    if pg:
        import pg8000.dbapi
        return (pg8000.dbapi.Error, OSError)
    return (sqlite3.Error,)


def _sqlite_connect(path, write, wait):
    if not write:
        if not os.path.exists(path):
            raise StoreError("%s: no such database (ingest records first)" % path)
        uri = "file:%s?mode=ro" % _uri_path(path)
    else:
        if os.path.exists(path):
            st = os.stat(path)
            # Checked by mode, not os.access(): as root every file is writable, yet a file
            # made read-only is meant to stay as it is.
            if not st.st_mode & 0o222:
                raise StoreError("%s: database is read-only (no write permission); nothing "
                                 "was stored" % path)
        uri = "file:%s?mode=rwc" % _uri_path(path)
    try:
        conn = sqlite3.connect(uri, uri=True, timeout=wait, isolation_level=None)
        conn.execute("PRAGMA schema_version")   # fails here on a file that is no database
    except sqlite3.Error as e:
        raise StoreError("%s: cannot open database: %s" % (path, e))
    # isolation_level=None: transactions are begun explicitly (BEGIN IMMEDIATE) in Store._run;
    # commit() and rollback() still end them.
    return conn


def _uri_path(path):
    import urllib.parse
    return urllib.parse.quote(os.path.abspath(path))


def _pg_connect(url, wait):
    """postgresql://user[:password]@host[:port]/dbname, or ?host=/socket/dir for a unix
    socket; the password may also come from PGPASSWORD."""
    import urllib.parse
    try:
        import pg8000.dbapi
    except ImportError:
        raise StoreError("PostgreSQL needs the pg8000 package (pip install -r requirements.txt)")
    u = urllib.parse.urlsplit(url)
    q = urllib.parse.parse_qs(u.query)
    db = urllib.parse.unquote(u.path.lstrip("/"))
    if not db or not u.username:
        raise StoreError("%s: expected postgresql://user@host:port/dbname" % describe(url))
    kw = {"user": urllib.parse.unquote(u.username), "database": db,
          "timeout": max(wait, 1.0)}
    pw = u.password or os.environ.get("PGPASSWORD")
    if pw:
        kw["password"] = urllib.parse.unquote(pw)
    port = u.port or 5432
    if "host" in q and q["host"][0].startswith("/"):
        kw["unix_sock"] = os.path.join(q["host"][0], ".s.PGSQL.%d" % port)
    else:
        kw["host"] = u.hostname or "localhost"
        kw["port"] = port
    where = kw.get("unix_sock") or "%s:%d" % (kw["host"], port)
    try:
        return pg8000.dbapi.connect(**kw)
    except (pg8000.dbapi.Error, OSError) as e:
        msg = e.args[0] if e.args else e
        if isinstance(msg, dict):
            msg = msg.get("M", msg)
        raise StoreError("%s: cannot connect to %s: %s" % (describe(url), where, msg))
