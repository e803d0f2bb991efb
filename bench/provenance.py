"""``python -m bench.provenance show | compare DIR_A DIR_B | backfill DIR K=V ...``: the
provenance of results (see :mod:`bench.core._provenance`)."""

from .core._provenance import main

if __name__ == "__main__":
    raise SystemExit(main())
