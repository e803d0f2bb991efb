"""Command line of decon-bench: ``python -m bench <verb>`` (also the ``decon-bench`` script).

Verbs: list, run, sweep, preflight, figures, report, perf, stability, bench, estimate, campaign,
compare (``--scores``: predictions beside the reference), data (export, verify), score. A bad
name or value, a run that can never run (e.g. leapfrog on a first-order model) or a results
folder that cannot be used prints one line ``error: ...`` on stderr and exits with code 2,
without a traceback. A write that fails during a sweep (full disk) stops it with one line and
exit code 1 (run it again to resume); ``report`` and ``figures`` on a folder without runs say
so and exit with code 1. A damaged row file is named in a one-line ``warning: ...`` and set
aside (see bench.core._store).
"""

from __future__ import annotations

import argparse
import json
import signal
import sys
import warnings
from pathlib import Path

from . import _adhoc, _score  # _score registers the verb score
from ._compare import OWN_DIR, reference_dir
from .core import (
    PROFILES,
    check_choice,
    check_sweep_args,
    commands,
    int_arg,
    seed_list,
    sweep_from_args,
    sweep_options,
    usable_results,
)


class UsageError(Exception):
    """A bad command-line input: reported in one line, exit code 2."""


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, no usage dump
        raise UsageError(message)


def _parser() -> argparse.ArgumentParser:
    p = _Parser(prog="python -m bench", description=__doc__)
    p.add_argument(
        "--results",
        default=str(OWN_DIR),
        help=f"results directory (default {OWN_DIR}/, git-ignored: your runs; the committed "
        "reference results are under results/reference/, read-only)",
    )
    p.add_argument(
        "--model-module",
        action="append",
        default=[],
        metavar="PKG.MODULE",
        help="import this module first: a plug-in that registers models (models.register); "
        "repeatable (also $DECON_MODEL_MODULES, comma-separated)",
    )
    sub = p.add_subparsers(dest="verb", required=True, parser_class=_Parser)

    sub.add_parser("list", help="systems, models, experiments, profiles")

    _adhoc.add_arguments(
        sub.add_parser("run", help="one ad-hoc run: print its metrics and store its row")
    )

    s = sub.add_parser("sweep", help="run an experiment's runs not yet stored")
    s.add_argument("experiment", nargs="?")
    s.add_argument("--all", action="store_true", help="every registered experiment")
    sweep_options(s, default_profile="quick")
    s.add_argument(
        "--seeds",
        default=None,
        metavar="5,6,7",
        help="these seeds instead of the profile's: integers and ranges, comma-separated "
        "(e.g. quick's replication seeds 5-9, or 0-4,7)",
    )

    pf = sub.add_parser(
        "preflight",
        help="every cell of an experiment (or --all) at a profile's sizes, trained a few steps "
        "and not stored: what fails, before a long campaign",
    )
    pf.add_argument("experiment", nargs="?")
    pf.add_argument("--all", action="store_true", help="every registered experiment")
    pf.add_argument("--profile", default="paper-core", help=f"one of {', '.join(PROFILES)}")
    pf.add_argument("--steps", type=int_arg("steps"), default=2, help="training steps (2)")
    pf.add_argument("--models", default=None, metavar="A,B", help="as sweep's --models")

    cm = sub.add_parser(
        "compare",
        help="two results folders side by side: claims, cells, runs (default: the reference "
        "of the results' profile against --results)",
    )
    cm.add_argument(
        "a", nargs="?", help="the reference folder (default: results/reference/<profile>)"
    )
    cm.add_argument("b", nargs="?", help="the folder to check (default: --results)")
    cm.add_argument("--out", default=None, help="also write the comparison (Markdown) here")
    _score.compare_arguments(cm)

    for verb, what in (("figures", "regenerate figures and tables"), ("report", "write REPORT.md")):
        sub.add_parser(verb, help=f"{what} from the stored runs").add_argument(
            "--profile",
            dest="report_profile",
            metavar="NAME",
            help="whose runs (default: the profile with the most rows; a line names the others)",
        )
    for c in commands():  # the verbs the studies register
        c.add_arguments(sub.add_parser(c.name, help=c.help, description=c.description))

    da = sub.add_parser("data", help="export a profile's datasets with a card; verify a folder")
    dsub = da.add_subparsers(dest="data_verb", required=True, parser_class=_Parser)
    de = dsub.add_parser("export", help="the train and test arrays of a system at a profile")
    de.add_argument("system", help="a system name (python -m bench list)")
    de.add_argument("--k", type=int_arg("k"), default=None, help="only this k (links/masses)")
    de.add_argument("--profile", default="quick", help=f"one of {', '.join(PROFILES)}")
    de.add_argument(
        "--seeds", default=None, metavar="0,1", help="only these seeds (0,1 or 0-4 or 0-4,7)"
    )
    de.add_argument("--format", default="npz", help="npz (default) or hdf5")
    de.add_argument("--out", required=True, help="the folder to write (new or empty)")
    de.add_argument("--force", action="store_true", help="write into a non-empty folder")
    dv = dsub.add_parser("verify", help="check an exported folder against its card")
    dv.add_argument("folder")
    dm = dsub.add_parser(
        "mujoco",
        help="train the SAC policy on a MuJoCo task (resumable) and save its recorded episodes "
        "with a card (systems.mujoco_data)",
    )
    dm.add_argument("task", help="a task of Fig. 7, e.g. HopperFull-v0")
    dm.add_argument("--steps", type=int_arg("steps"), default=200_000, help="env steps")
    dm.add_argument("--seed", type=int_arg("seed"), default=0, help="the collection seed")
    dm.add_argument("--out", default=None, help="the folder (default: systems.mujoco_data's)")

    b = sub.add_parser(
        "bench",
        help="sweep every experiment (or those of --papers), the stability cases, then figures "
        "and report",
    )
    sweep_options(b, default_profile="quick")
    b.add_argument("--skip-stability", action="store_true", help="do not run the stability cases")
    b.add_argument(
        "--papers",
        default=None,
        metavar="A,B",
        help="only the experiments of these papers: deconstructing (Gruver et al. 2022, with "
        "the stability cases), hnn, lnn, vin (its seeds); default all",
    )
    b.add_argument(
        "--no-compare",
        action="store_true",
        help="do not compare with the reference of the profile (results/reference/<profile>)",
    )
    return p


def _cmd_list(args) -> int:
    import models
    import systems

    from .core import available

    print("systems:     " + ", ".join(systems.available()))
    print("models:      " + ", ".join(models.available()))
    print("experiments: " + (", ".join(available()) or "(none registered)"))
    print("profiles:    " + ", ".join(PROFILES))
    return 0


def paper_list(given: str | None) -> tuple[str, ...]:
    """``--papers A,B`` as a tuple of :data:`bench.core._experiments.PAPERS` (None: all)."""
    from .core import PAPERS

    if given is None:
        return PAPERS
    names = tuple(x.strip() for x in given.split(",") if x.strip())
    if not names:
        raise ValueError(f"--papers needs at least one of {', '.join(PAPERS)}")
    for name in names:
        check_choice("paper (--papers)", name, PAPERS)
    return names


def _sweep_names(args) -> list[str]:
    from .core import available, get

    if args.verb == "bench":
        papers = paper_list(getattr(args, "papers", None))
        return [n for n in available() if get(n).paper in papers]
    if getattr(args, "all", False):
        return available()
    if not args.experiment:
        raise UsageError("sweep needs an experiment name or --all")
    get(args.experiment)  # ValueError with the allowed names
    return [args.experiment]


def _do_sweep(args, names) -> int:
    check_sweep_args(args)
    if not names:
        print("no experiments yet")
        return 0
    usable_results(args)
    # longest runs first (the registered cost model): the workers finish together
    seeds = seed_list(getattr(args, "seeds", None))
    res = sweep_from_args(args, names, seeds=seeds)
    for name, rows in res.items():
        counts = {}
        for r in rows:
            counts[r["status"]] = counts.get(r["status"], 0) + 1
        print(f"{name}: {len(rows)} new runs {counts}")
    return 0


def _cmd_preflight(args) -> int:
    from ._preflight import preflight
    from .core import model_list

    check_choice("profile", args.profile, list(PROFILES))
    rows = preflight(_sweep_names(args), args.profile, steps=args.steps, models=model_list(args))
    failed = [r for r in rows if r["status"] == "failed"]
    print(f"preflight at {args.profile}: {len(rows)} cells, {len(failed)} failed")
    return 1 if failed else 0


class NoRuns(Exception):
    """No stored runs to draw or report: one line, exit code 1."""


def _stored_runs(args, verb: str, action: str):
    """The stored runs (NoRuns where none); warn about row files that did not read."""
    from .core import (
        DAMAGED,
        ROWS,
        check_results_dir,
        load_runs,
        rebuild_tables,
        stale_tables,
        unread_rows,
    )

    results = check_results_dir(args.results, create=False)
    runs = load_runs(results)  # damaged row files are named and set aside here
    stale = stale_tables(results)
    if stale:  # tables others read (pandas users, the figures of a fresh clone): rebuild them
        what = ", ".join(f"{name} ({why})" for name, why in stale)
        print(f"warning: rebuilt from the row files: {what}", file=sys.stderr)
        rebuild_tables(results)
    unread = unread_rows(results)
    if unread:
        print(
            f"warning: {len(unread)} stored row file(s) could not be read and are left out of "
            f"the {verb} (kept in {results / ROWS / DAMAGED}; the next sweep "
            "reruns their runs)",
            file=sys.stderr,
        )
    if runs.empty:
        profiles = ", ".join(PROFILES)
        raise NoRuns(
            f"no runs stored in {results} for any profile ({profiles}): nothing to {action}; "
            "run `python -m bench sweep --all --profile <profile>` first"
        )
    return runs


def _cmd_figures(args) -> int:
    from ._report import make_figures, report_profile

    runs = _stored_runs(args, "figures", "draw")
    make_figures(Path(args.results), report_profile(args, runs, "drawing"))
    return 0


def _cmd_report(args) -> int:
    from ._report import report_profile, write_report

    runs = _stored_runs(args, "report", "report")
    write_report(Path(args.results), profile=report_profile(args, runs, "reporting"))
    return 0


def _cmd_bench(args) -> int:
    import time

    names = _sweep_names(args)
    if not names:
        check_sweep_args(args)
        print("no experiments yet")
        return 0
    from .core import SCHEMA_VERSION, done_hashes, provenance

    before = len(done_hashes(Path(args.results)))
    start = time.time()
    _do_sweep(args, names)
    swept = time.time()
    executed = len(done_hashes(Path(args.results))) - before
    stability = next((c for c in commands() if c.name == "stability"), None)
    with_stability = "deconstructing" in paper_list(getattr(args, "papers", None))
    if not args.skip_stability and with_stability and stability is not None:
        args.case = None
        stability.run(args)
    meta = {
        "start": start,
        "end": time.time(),
        "wall_seconds": time.time() - start,
        "sweep_seconds": swept - start,
        "runs_executed": executed,  # runs already stored were skipped, not timed
        "stability_seconds": time.time() - swept,
        "profile": args.profile,
        "executor": args.executor,
        "workers": args.workers,
        "ensemble": args.ensemble,
        "experiments": names,
        "papers": list(paper_list(getattr(args, "papers", None))),
        "provenance": provenance(),  # this process's versions, device and commit
        "schema_version": SCHEMA_VERSION,
    }
    results = Path(args.results)
    results.mkdir(parents=True, exist_ok=True)
    (results / "bench_meta.json").write_text(json.dumps(meta, indent=1))
    args.swept_profile = args.profile  # figures and report show it where its rows are stored
    _cmd_figures(args)
    _cmd_report(args)
    print(f"bench: {meta['wall_seconds'] / 60:.1f} min (sweep and stability), report written")
    ref = reference_dir(args.profile)
    if args.no_compare or ref is None or not ref.is_dir():
        return 0
    if ref.resolve() == results.resolve():
        return 0  # regenerating the reference itself
    args.a, args.b, args.out = str(ref), str(results), str(results / "COMPARE.md")
    return _cmd_compare(args)


def _data_mujoco(args) -> int:
    import time

    import systems

    task = systems.mujoco_task(args.task)  # a one-line error naming the tasks
    path = systems.mujoco_data.data_path(task.name, args.out)
    if path.with_suffix(".json").exists():
        done = json.loads(path.with_suffix(".json").read_text()).get("policy_training", {})
        if (done.get("steps"), done.get("seed")) == (args.steps, args.seed):
            print(f"{path}: collected already ({args.steps} steps, seed {args.seed})")
            return 0
    t0 = time.perf_counter()

    def progress(n, info):
        shown = ", ".join(f"{k} {v:.4g}" for k, v in info.items())
        print(f"{args.task}: {n}/{args.steps} steps, {shown}", file=sys.stderr, flush=True)

    import collect

    path = collect.collect_task(
        args.task, args.steps, seed=args.seed, folder=args.out, progress=progress
    )
    card = json.loads(path.with_suffix(".json").read_text())
    size = path.stat().st_size / 1e6
    print(
        f"{path}: {card['collection']['transitions']} transitions, {size:.1f} MB, policy "
        f"return {card['policy_return']:.1f}, {time.perf_counter() - t0:.0f} s"
    )
    return 0


def _cmd_data(args) -> int:
    """``data export``: write the datasets and print the folder; ``data verify``: one line per
    array that differs from the card, exit code 1 if any."""
    from . import _data, data_loader

    if args.data_verb == "verify":
        return data_loader.main(["verify", args.folder])
    if args.data_verb == "mujoco":
        return _data_mujoco(args)
    check_choice("profile", args.profile, list(PROFILES))
    seeds = seed_list(args.seeds)
    card = _data.export(
        args.system,
        args.out,
        profile=args.profile,
        k=args.k,
        seeds=seeds,
        fmt=args.format,
        force=args.force,
        progress=lambda m: print(m, file=sys.stderr),
    )
    for note in card["notes"]:
        print(f"note: {note}")
    n = len(card["datasets"])
    print(f"{args.out}: {n} dataset(s), {len(card['arrays'])} arrays, card.json and README.md")
    return 0


def _cmd_compare(args) -> int:
    """Print the claims table and the one-line summary of ``compare`` (the whole comparison
    with ``--out``)."""
    from ._compare import compare
    from .core import load_tables

    b = Path(args.b or args.results)
    a = args.a
    if a is None:
        profile = load_tables(b)[2] if b.is_dir() else None
        ref = reference_dir(profile) if profile else None
        if ref is None or not ref.is_dir():
            raise ValueError(
                f"no reference folder for the runs of {b} (profile {profile}); name one: "
                "python -m bench compare A B"
            )
        a = ref
    comp = compare(a, b)
    text = comp.markdown()
    if args.out:
        Path(args.out).parent.mkdir(parents=True, exist_ok=True)
        Path(args.out).write_text(text)
    claims = text[text.index("## Claims") : text.index("## Cells")].rstrip()
    print(claims)
    for w in comp.warnings:
        print(f"warning: {w}", file=sys.stderr)
    if args.out:
        print(f"cells and runs: {args.out}")
    print(comp.summary)
    return 0


def _one_line_warning(message, category, filename, lineno, file=None, line=None):
    from .core import DamagedRowWarning

    if issubclass(category, DamagedRowWarning):
        print(f"warning: {message}", file=sys.stderr if file is None else file)
    else:
        _show_warning(message, category, filename, lineno, file, line)


_show_warning = warnings.showwarning


def main(argv: list[str] | None = None) -> int:
    """Entry point; returns the exit code (2 for bad input, 1 for no runs or a failed write)."""
    from .core import StorageError, WorkerDied, setup_process

    setup_process()
    if hasattr(signal, "SIGXFSZ"):  # a file-size limit: an OSError (EFBIG), not a core dump
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    try:
        with warnings.catch_warnings():
            warnings.showwarning = _one_line_warning
            return _main(argv)
    except (UsageError, ValueError) as e:
        print(f"error: {str(e).splitlines()[0] if str(e) else type(e).__name__}", file=sys.stderr)
        return 2
    except (NoRuns, StorageError, WorkerDied) as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    except OSError as e:  # any other failed read or write: one line, no traceback
        where = f"{e.filename}: " if e.filename else ""
        print(f"error: {where}{e.strerror or e}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130


def _main(argv) -> int:
    args = _parser().parse_args(argv)
    if args.model_module:  # the sweep's worker processes inherit the environment
        import os

        import models

        given = [m for item in args.model_module for m in item.split(",") if m.strip()]
        old = [m for m in os.environ.get(models.MODULES_ENV, "").split(",") if m]
        os.environ[models.MODULES_ENV] = ",".join(dict.fromkeys([*old, *given]))
        models.load_plugins()
    if args.verb == "list":
        return _cmd_list(args)
    if args.verb == "run":
        return _adhoc.run(args)
    if args.verb == "sweep":
        return _do_sweep(args, _sweep_names(args))
    if args.verb == "preflight":
        return _cmd_preflight(args)
    verbs = {
        "figures": _cmd_figures,
        "report": _cmd_report,
        "bench": _cmd_bench,
        "compare": _score.compare_verb(_cmd_compare),
        "data": _cmd_data,
    }
    verbs.update({c.name: c.run for c in commands()})
    return verbs[args.verb](args)
