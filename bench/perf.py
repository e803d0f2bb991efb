"""``python -m bench.perf``: the performance benchmark (see :mod:`bench._perf`)."""

from ._perf import main

if __name__ == "__main__":
    raise SystemExit(main())
