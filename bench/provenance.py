"""``python -m bench.provenance show | compare DIR_A DIR_B | backfill DIR K=V ...``: the
provenance of results (see :mod:`bench.core._provenance`)."""

from .core import provenance_main as main

if __name__ == "__main__":
    raise SystemExit(main())
