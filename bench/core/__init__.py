"""The core of the benchmark: run configurations and experiments, the run pipeline (build ->
train -> evaluate -> record, in ``_execute``), training, metrics, the sweep runner, the results
store, provenance and the one query layer over stored tables. Nothing here imports the studies,
the CLI or the report (studies register themselves).

The rest of the suite imports the core's names from here (``from bench.core import RunConfig``),
never from its private modules. A name loads its module on first access (PEP 562), so importing
``bench.core`` imports none of them, nor jax.
"""

import importlib

# The public names, by the private module that holds them.
_MODULES = {
    # files written whole or not at all
    "_atomic": "atomic_write write_json",
    # training on fresh states drawn from a box
    "_box": "BoxObjective BoxStates",
    # the build step of a state run
    "_build": "build_run model_of",
    # a run as data: RunConfig, its field vocabularies and its hashes
    "_config": "RunConfig field_names",
    # the fields' vocabularies and the one-line check of a name
    "_vocab": "COORDINATES DTYPES LOSSES OBSERVATIONS PIXEL_SIZE TRAIN_TARGETS check_choice",
    # runs that differ only in seed, learning rate or noise, trained as one program
    "_ensemble": "group_key plan_groups train_ensemble",
    # process settings made by entry points: 64-bit mode, threads, the compilation cache
    "_env": (
        "bound_compiled_programs configure_compilation_cache configure_numerics cpu_count "
        "setup_process"
    ),
    # one-line error messages and the errors that stop a sweep
    "_errors": "StorageError WorkerDied one_line storage_error",
    # the evaluate step of a state run
    "_evaluate": "CHECKPOINT_METRICS eval_integrator",
    # one run as a pipeline: build -> train -> evaluate -> record
    "_execute": "execute_run",
    # the observation kinds of a run (what the models see) and their registry
    "_observation": "Member Observation observation_kinds register_observation",
    # experiments as data, their profiles, papers and selections
    "_experiments": (
        "Experiment PAPERS PROFILES REPLICATION_SEEDS SELECTIONS available expand get "
        "is_supplementary profile_defaults reading_of register replication_seeds"
    ),
    # the train step of a state run, through the parameter cache
    "_fit": "checkpoint_steps objective train_cached train_config",
    # runs that learn from single frames
    "_frames": "FRAME_METRICS WindowDraws seed_elbo",
    # metrics of a predicted rollout against the truth
    "_metrics": (
        "CLAMP energies energy_mse energy_pct_max_pe energy_pct_max_pe_last energy_violation "
        "energy_violation_curve geometric_mean mse n_params perturbed_floor relative_error "
        "rollout_error state_difference symplectic_error valid_prediction_time wrap"
    ),
    # command-line options shared by the CLI's verbs and the studies'
    "_options": (
        "check_sweep_args float_arg int_arg model_list seed_list sweep_from_args sweep_options "
        "usable_results"
    ),
    # the update rule and its learning-rate schedule
    "_optim": "lr_schedule optimizer",
    # the parameter cache
    "_params": (
        "BLOW_UP_RISE DATA_TAG RESUME cache_key code_fingerprint loss_rise params_dir result_meta "
        "saved_by_this_code"
    ),
    # the evaluate step of a pixel run
    "_pixel_eval": "evaluate_pixels latent_map",
    # runs that learn from pixels: the build and train steps
    "_pixels": (
        "AE_LOSS CC_LOSS DYN_LOSS PIXEL_METRICS PixelObjective WEIGHT_DECAY seed_loss train_pixels"
    ),
    # the software and hardware that produced a result
    "_provenance": (
        "PROVENANCE_COLUMNS compare_provenance machine_key provenance provenance_markdown"
    ),
    # the one query layer over the stored tables
    "_query": (
        "aggregate cell_key check_profile chosen_profile describe_profiles experiment_rows "
        "initial_state labelled load_tables option params_of parse_pairs pick_profile plain "
        "profile_counts row_cell_keys select variant"
    ),
    # the record step of a run: its row and artifact folder
    "_record": "base_row training_columns",
    # interrupted training resumes where it was last saved
    "_resume": "RECORD ResumePoint",
    # whether the registered models can run a configuration
    "_runnable": "check_runnable",
    # sweeps: many runs, the stored ones skipped, each row written as it arrives
    "_runner": "imap_unordered sweep to_velocity worker_pool",
    # the results tables' columns
    "_schema": "SCHEMA_VERSION",
    # the results store: row files and the tables rebuilt from them
    "_store": (
        "DAMAGED DamagedRowWarning OWN_DIR REFERENCE_DIRS REFERENCE_ROOT ROWS check_results_dir "
        "compare_folders done_hashes holds_runs load_checkpoints load_curves load_runs read_rows "
        "rebuild_tables reference_dir rows_digest rows_frame runs_of stale_tables unread_rows"
    ),
    # the registry of studies, their command-line verbs and report sections
    "_studies": (
        "Command ReportContext ReportSection Study commands register_command "
        "register_cost_model register_section register_study report_sections studies"
    ),
    # what a training fits by default: chunks of states, their loss, batches and arrays
    "_objective": "Batches loss_fn prepare",
    # the one training loop: one run or an ensemble, as one compiled program
    "_train": "Training make_step train",
    # a training's settings and result
    "_train_config": "TrainConfig TrainResult",
}
# Public under another name than their module's: there a run kind's step or columns, named as
# every kind names them (build, train_config, METRIC_COLUMNS), or a word its module makes plain.
_RENAMED = {
    "CONTROLLED": ("_controlled", "CONTROLLED"),
    "CONTROLLED_COLUMNS": ("_controlled", "METRIC_COLUMNS"),
    "controlled_mse": ("_controlled", "normalised_mse"),
    "controlled_predictor": ("_controlled", "predictor"),
    "MEASURED_COLUMNS": ("_measured", "METRIC_COLUMNS"),
    "build_pixels": ("_pixels", "build"),
    "ensemble_enabled": ("_ensemble", "enabled"),
    "pixel_train_config": ("_pixels", "train_config"),
    "provenance_main": ("_provenance", "main"),
}
_WHERE = {name: (module, name) for module, names in _MODULES.items() for name in names.split()}
_WHERE |= _RENAMED

__all__ = [*_WHERE]


def __getattr__(name: str):
    # Not cached here: a name patched in its module (as tests do) reads the same through here.
    try:
        module, attr = _WHERE[name]
    except KeyError:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}") from None
    return getattr(importlib.import_module(f"{__name__}.{module}"), attr)


def __dir__():
    return sorted({*globals(), *__all__})
