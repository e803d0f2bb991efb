"""``python -m bench.studies.perf``: the performance benchmark's own command line (``--help``
lists its options; :mod:`bench.studies.perf`)."""

from ._main import main

if __name__ == "__main__":
    raise SystemExit(main())
