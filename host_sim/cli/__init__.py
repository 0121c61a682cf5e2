"""Command implementations for `python -m host_sim`; each module has main(argv) -> exit code."""
