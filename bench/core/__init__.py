"""The core of the benchmark: run configurations and experiments, the run pipeline (build ->
train -> evaluate -> record, in ``_execute``), training, metrics, the sweep runner, the results
store, provenance and the one query layer over stored tables. Nothing here imports the studies,
the CLI or the report (studies register themselves). The public names are re-exported by
``bench``; this ``__init__`` imports nothing, so that ``bench`` can pin threads before jax loads.
"""
