"""``python -m bench.perf``: the performance benchmark (see :mod:`bench.studies.perf`)."""

from .studies.perf import main

if __name__ == "__main__":
    raise SystemExit(main())
