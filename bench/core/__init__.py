"""The core of the benchmark: experiments and run configurations (``_experiments``), training
(``_train``), ensembles (``_ensemble``), metrics (``_metrics``), the runner (``_runner``), the
store (``_store``), provenance (``_provenance``), the environment (``_env``), storage errors
(``_errors``), the one query layer over the stored tables (``_query``) and the study registry
(``_studies``).

Nothing here imports ``bench.studies``, the CLI or the report: studies, above this layer,
register themselves. The public names are re-exported by ``bench``; this ``__init__`` imports
nothing, so that ``bench`` can pin threads before any module here loads jax.
"""
