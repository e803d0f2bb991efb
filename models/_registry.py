"""The model registry: every registered model, each assembled from the bias parts of the
sibling modules, one family per file (``_node``, ``_resnet``, ``_hnn``, ``_lnn``, ``_vin``,
``_forced``, ``_trivial``).

| name         | biases                                                                   |
| ------------ | ------------------------------------------------------------------------ |
| node         | ODE: dz/dt = MLP(z)                                                      |
| node_so      | ODE + second order: dq/dt = qdot, dqdot/dt = MLP(q, qdot)               |
| node_so_pq   | node_so as the Deconstructing paper builds it: (q, p) via a learned M^-1  |
| hnn          | ODE + energy + exact symplectic: J grad H, general H(q, p)               |
| hnn_so       | hnn + second order: separable H = 1/2 p^T M^-1(q) p + V(q)               |
| mixture_hnn  | the paper's damped comparator: hnn_so field + a free MLP field in (q, p) |
| node_symreg  | node + soft symplectic penalty weight * mean ||J DF - (J DF)^T||^2       |
| node_so_symreg | canonical NODE+SO: dq/dt = M^-1(q) p, dp/dt = MLP(q, p), + the penalty |
| lnn          | ODE + second order + energy: Euler-Lagrange of a learned L(q, qdot)      |
| vin          | discrete + variational: Verlet step of L = 1/2 v^T M v - U(q)            |
| vin_implicit | discrete + variational: midpoint DEL step of a general learned L(q, v)   |
| resnet       | discrete, free: z_{n+1} = z_n + MLP(z_n)                                 |
| hnn_force    | the paper's controlled HNN: hnn_so field + a free force F(q, p, u) on dp/dt |
| hnn_force_paper | hnn_force as the paper's code runs it: M = I, grad H in standardised z  |
| constant_velocity | trivial, no parameters: q(t) = q0 + t qdot0 (see ``_trivial``)      |
| at_rest      | trivial, no parameters: q(t) = q0, qdot(t) = 0                           |

``hnn`` takes ``momentum_map`` (default True: p = M(q) qdot with a learned M in a velocity
scene); ``momentum_map=False`` is the LNN seed's naive baseline, H(q, qdot) with qdot standing
in for p and dz/dt = J grad H on (q, qdot). ``hnn_force`` takes ``inverse_mass_floor``
(default 1e-4: the floor under its M^-1's spectrum). ``hnn`` (its H network), ``hnn_so`` (both
networks), ``node`` and ``lnn`` take ``init`` (``models._mlp.INITS``; ``hnn_seed``: the HNN
seed's PyTorch initialisation; ``paper``: the Deconstructing paper's, node_so_pq's default);
``hnn`` also ``inverse_mass`` (learn M^-1 = L L^T + 1e-4 I, as that paper's code does, instead
of M's factor).

The structured models (hnn, hnn_so, lnn, vin, vin_implicit) add the :class:`Dissipation`
part when the scene is damped (or ``dissipation=True``).

In a controlled scene (``Scene.n_controls`` > 0) only the models with a part that reads u
(``spec(name).controls``: the free networks of node, node_so, node_symreg, node_so_symreg,
mixture_hnn, resnet, and the force of hnn_force and hnn_force_paper) can be built; see
``models._features``.
"""

from __future__ import annotations

import difflib
from collections.abc import Callable
from typing import NamedTuple

import equinox as eqx
import jax

from ._base import AbstractContinuousModel, AbstractDiscreteModel
from ._forced import ForcedHNN, ReferenceForcedHNN
from ._hnn import HNN, MixtureHNN, SeparableHNN
from ._lnn import LNN
from ._mlp import ACTIVATIONS, DTYPES, INITS
from ._node import CanonicalSecondOrderODE, MomentumSecondOrderODE, NeuralODE, SecondOrderODE
from ._options import _boolean, _choice, _positive_float, _positive_int, _strictly_positive_float
from ._resnet import ResNet
from ._scalar import SOLVES
from ._scene import Scene
from ._trivial import AtRest, ConstantVelocity
from ._vin import VIN, ImplicitVIN


def _build_hnn(
    scene,
    *a,
    key,
    dissipation,
    separable=False,
    momentum_map=True,
    init="orthogonal",
    inverse_mass=False,
):
    if separable and not scene.canonical:
        return SeparableHNN(scene, *a, key=key, dissipation=dissipation, init=init)
    return HNN(
        scene,
        *a,
        key=key,
        separable=separable,
        dissipation=dissipation,
        momentum_map=momentum_map,
        init=init,
        inverse_mass=inverse_mass,
    )


def _trivial(cls):
    def build(s, width, depth, activation, dtype, *, key, dissipation):
        return cls(s, dtype)

    return build


class _Entry(NamedTuple):
    """A registered model: its class (whose markers the spec reads), how to build it, its
    options (name -> validator), whether it takes a dissipation term (the structured models),
    the coordinates it needs (None: either) and its default activation."""

    cls: type
    build: Callable
    options: dict = {}
    structured: bool = False
    needs: str | None = None
    activation: str = "tanh"


def _plain(cls):
    """The builder of a model class that takes no dissipation term."""

    def build(s, *a, key, dissipation, **options):
        return cls(s, *a, key=key, **options)

    return build


_V, _P = "velocity", "momentum"
_REGISTRY = {
    "node": _Entry(NeuralODE, _plain(NeuralODE), {"init": _choice("init", INITS)}),
    "node_so": _Entry(SecondOrderODE, _plain(SecondOrderODE)),
    "node_so_pq": _Entry(
        MomentumSecondOrderODE,
        _plain(MomentumSecondOrderODE),
        {"init": _choice("init", INITS)},
        needs=_V,
    ),
    "hnn": _Entry(
        HNN,
        _build_hnn,
        {
            "momentum_map": _boolean("momentum_map"),
            "init": _choice("init", INITS),
            "inverse_mass": _boolean("inverse_mass"),
        },
        True,
    ),
    "hnn_so": _Entry(
        SeparableHNN,
        lambda s, *a, key, dissipation, init="orthogonal": _build_hnn(
            s, *a, key=key, separable=True, dissipation=dissipation, init=init
        ),
        {"init": _choice("init", INITS)},
        structured=True,
    ),
    "mixture_hnn": _Entry(MixtureHNN, _plain(MixtureHNN)),
    "node_symreg": _Entry(
        NeuralODE,
        lambda s, *a, key, dissipation, weight=1.0: NeuralODE(s, *a, key=key, weight=weight),
        {"weight": _positive_float("weight")},
    ),
    "node_so_symreg": _Entry(
        CanonicalSecondOrderODE,
        lambda s, *a, key, dissipation, weight=1.0: CanonicalSecondOrderODE(
            s, *a, key=key, weight=weight
        ),
        {"weight": _positive_float("weight")},
        needs=_P,
    ),
    "lnn": _Entry(
        LNN,
        LNN,
        {
            "solve": _choice("solve", SOLVES),
            "eps": _positive_float("eps"),
            "init": _choice("init", INITS),
            "kinetic_prior": _positive_float("kinetic_prior"),
        },
        True,
        _V,
        "softplus",
    ),
    "vin": _Entry(VIN, VIN, {}, True, _V),
    "vin_implicit": _Entry(
        ImplicitVIN, ImplicitVIN, {"newton_steps": _positive_int("newton_steps")}, True, _V
    ),
    "resnet": _Entry(ResNet, _plain(ResNet)),
    "hnn_force": _Entry(
        ForcedHNN,
        _plain(ForcedHNN),
        {"inverse_mass_floor": _strictly_positive_float("inverse_mass_floor")},
        needs=_V,
    ),
    "hnn_force_paper": _Entry(ReferenceForcedHNN, _plain(ReferenceForcedHNN), needs=_V),
    "constant_velocity": _Entry(ConstantVelocity, _trivial(ConstantVelocity)),
    "at_rest": _Entry(AtRest, _trivial(AtRest)),
}


BUILT_IN = tuple(_REGISTRY)
ENTRY_POINT_GROUP = "decon_bench.models"
MODULES_ENV = "DECON_MODEL_MODULES"  # comma-separated plug-in modules (--model-module)
_PLUGINS: set[str] = set()  # plug-in sources already loaded ("ep:<name>", "module:<name>")
_SOURCES: dict[str, str] = {}  # plug-in name -> fingerprint of its source when registered
_MODULES: dict[str, str] = {}  # plug-in name -> the module that registered it
_GENERATION = [0]  # counts the registrations: models.spec caches what it read per generation


# The suite's own top-level packages: the parameter cache fingerprints their source already.
_OWN_PACKAGES = ("models", "systems", "bench")


def _plugin_source(module_names, objects) -> str:
    """A short sha256 of the source a plug-in's model comes from: for each module in
    ``module_names`` outside the suite, every ``.py`` file of its top-level package (a
    plug-in's helpers count: ``mylab.nets`` reads the whole of ``mylab``), or its one file; a
    module without a file (defined in a notebook) gives the source of ``objects`` instead."""
    import hashlib
    import inspect
    import sys
    from pathlib import Path

    h = hashlib.sha256()
    tops = sorted({str(m).partition(".")[0] for m in module_names if m} - set(_OWN_PACKAGES))
    for top in tops:
        module = sys.modules.get(top)
        roots = list(getattr(module, "__path__", None) or [])  # a package's folders
        files = [(Path(r), f) for r in roots for f in sorted(Path(r).rglob("*.py"))]
        if not roots and getattr(module, "__file__", None):
            files = [(Path(module.__file__).parent, Path(module.__file__))]
        for root, f in files:
            h.update(f"{top}/{f.relative_to(root)}\0".encode())
            h.update(f.read_bytes())
        if not files:
            for obj in objects:
                try:
                    h.update(inspect.getsource(obj).encode())
                except (OSError, TypeError):  # no source to be had: the name at least
                    h.update(f"{top}:{getattr(obj, '__qualname__', obj)}".encode())
    return h.hexdigest()[:16]


def plugin_fingerprint(name: str) -> str | None:
    """The fingerprint of the source of plug-in model ``name`` as it was registered (its
    class's, its builder's and the registering module's top-level packages, read when
    :func:`register` ran: the code this process runs), or None for a built-in (or unknown)
    model. The parameter cache and the stored rows of a plug-in model record it, so that a
    run whose plug-in was edited since is trained anew; the suite's own source is the
    parameter cache's code fingerprint."""
    load_plugins()
    return _SOURCES.get(name) if name in _REGISTRY else None


def plugin_modules(used=None) -> dict[str, list[str]]:
    """The plug-in modules this process loaded (``$DECON_MODEL_MODULES``/``--model-module``, and
    the modules that registered the plug-in models named in ``used``, every one if None; not
    ``__main__``), each with the ``sys.path`` folders its top-level package came from: what
    another process (a Ray worker, which inherits none of this one's imports) needs to load
    the same plug-ins with :func:`load_plugins`."""
    import sys
    from pathlib import Path

    names = [k.split(":", 1)[1] for k in sorted(_PLUGINS) if k.startswith("module:")]
    names += [m for n, m in _MODULES.items() if (used is None or n in used) and m != "__main__"]
    out: dict[str, list[str]] = {}
    for name in dict.fromkeys(n for n in names if n and n.partition(".")[0] not in _OWN_PACKAGES):
        top = sys.modules.get(name.partition(".")[0])
        roots = [Path(w).parent for w in getattr(top, "__path__", None) or []]  # a package
        if not roots and getattr(top, "__file__", None):  # a one-file module
            roots = [Path(top.__file__).parent]
        out[name] = list(dict.fromkeys(str(r) for r in roots))
    return out


def register(
    name: str,
    cls: type,
    *,
    build: Callable | None = None,
    options: dict | None = None,
    takes_dissipation: bool = False,
    coordinates: str | None = None,
    activation: str = "tanh",
) -> str:
    """Register a model from outside the suite under ``name``; returns ``name``.

    The contract (checked here, a one-line ValueError naming what is missing): ``cls`` is a
    subclass of :class:`AbstractContinuousModel` (a learned field ``vector_field(t, z, args)``)
    or :class:`AbstractDiscreteModel` (a learned map ``step(z, dt, args)``), with every
    abstract method implemented and a class attribute ``structure`` in (None, "hamiltonian",
    "lagrangian"); ``build(scene, width, depth, activation, dtype, *, key, dissipation,
    **options)`` returns an instance (default: ``cls(scene, width, depth, activation, dtype,
    key=key, **options)``); ``options`` maps each option name to a validator returning the
    value; ``takes_dissipation``: the model adds a dissipation term in damped scenes (then
    ``build`` receives ``dissipation``); ``coordinates``: None (either), "velocity" or
    "momentum". :func:`spec` reads its capabilities like a built-in's. Re-registering the
    same plug-in name replaces it; a built-in name cannot be taken.
    """
    import inspect
    import sys

    def bad(what: str):
        raise ValueError(f"model plug-in {name!r}: {what}")

    if not isinstance(name, str) or not name.isidentifier():
        bad("the name must be a Python identifier")
    if name in BUILT_IN:
        bad(f"the name is a built-in model; built-ins: {', '.join(BUILT_IN)}")
    if not isinstance(cls, type) or not issubclass(
        cls, AbstractContinuousModel | AbstractDiscreteModel
    ):
        bad(
            "the class must subclass models.AbstractContinuousModel (a vector field) or "
            "models.AbstractDiscreteModel (a map); got "
            f"{getattr(cls, '__name__', cls)!r}"
        )
    missing = sorted(getattr(cls, "__abstractmethods__", ()) or ())
    if missing:
        bad(f"{cls.__name__} does not implement {', '.join(missing)}")
    if getattr(cls, "structure", "?") not in (None, "hamiltonian", "lagrangian"):
        bad(f"{cls.__name__}.structure must be None, 'hamiltonian' or 'lagrangian'")
    if coordinates not in (None, _V, _P):
        bad(f"coordinates must be None, {_V!r} or {_P!r}; got {coordinates!r}")
    if activation not in ACTIVATIONS:
        bad(f"activation must be one of {sorted(ACTIVATIONS)}; got {activation!r}")
    options = dict(options or {})
    if not all(isinstance(k, str) and callable(v) for k, v in options.items()):
        bad("options must map option names to validator callables")
    if build is None:
        build = _plain(cls)
        target = cls
        probe = ("scene", 1, 1, "tanh", "float32")
        kwargs = {"key": None}
    else:
        target, probe, kwargs = (
            build,
            ("scene", 1, 1, "tanh", "float32"),
            {
                "key": None,
                "dissipation": False,
            },
        )
    if not callable(build):
        bad("build must be callable")
    try:
        inspect.signature(target).bind(*probe, **kwargs)
    except TypeError as e:
        bad(
            "build (or the class) must accept (scene, width, depth, activation, dtype, *, key"
            f"{', dissipation' if target is build else ''}, **options): {e}"
        )
    except ValueError:  # no signature available: trust it
        pass
    caller = sys._getframe(1).f_globals.get("__name__")  # the module that registers it
    source = _plugin_source(
        [getattr(cls, "__module__", None), getattr(build, "__module__", None), caller],
        [cls, build],
    )
    _REGISTRY[name] = _Entry(cls, build, options, bool(takes_dissipation), coordinates, activation)
    _SOURCES[name] = source
    _MODULES[name] = caller
    _GENERATION[0] += 1  # what models.spec read of the registry is stale now
    return name


_ENTRY_POINTS: list = []  # [the entry points of ENTRY_POINT_GROUP], once scanned


def load_plugins(modules: str | None = None) -> None:
    """Import the plug-in models, once each: the entry points of :data:`ENTRY_POINT_GROUP` and
    the modules named in ``$DECON_MODEL_MODULES`` (or ``modules``), comma-separated. A module
    registers its models on import (:func:`register`); an entry point that loads a callable
    is called. A plug-in that fails to import is a one-line ValueError naming it."""
    import importlib
    import os
    from importlib import metadata

    names = modules if modules is not None else os.environ.get(MODULES_ENV, "")
    todo = [("module:" + m.strip(), m.strip()) for m in names.split(",") if m.strip()]
    if not _ENTRY_POINTS:  # scanned once a process: a scan reads every installed package's
        # metadata (~7 ms), and available() is asked for every configuration of a sweep
        try:
            _ENTRY_POINTS.append(list(metadata.entry_points(group=ENTRY_POINT_GROUP)))
        except Exception:  # noqa: BLE001 - a broken environment must not stop the built-ins
            _ENTRY_POINTS.append([])
    todo += [("ep:" + ep.name, ep) for ep in _ENTRY_POINTS[0]]
    for key, what in todo:
        if key in _PLUGINS:
            continue
        _PLUGINS.add(key)
        try:
            obj = importlib.import_module(what) if isinstance(what, str) else what.load()
            if callable(obj) and not isinstance(obj, type):
                obj()
        except ValueError:
            raise
        except Exception as e:  # noqa: BLE001 - one line naming the plug-in
            source = (
                "DECON_MODEL_MODULES/--model-module"
                if isinstance(what, str)
                else (f"entry point {ENTRY_POINT_GROUP}")
            )
            raise ValueError(
                f"model plug-in {key.split(':', 1)[1]!r} ({source}) failed to load: "
                f"{type(e).__name__}: {str(e).splitlines()[0] if str(e) else ''}"
            ) from None


def available() -> list[str]:
    """Names of the registered models (built-ins, then plug-ins)."""
    load_plugins()
    return list(_REGISTRY)


def trivial_models() -> list[str]:
    """Names of the registered trivial predictors (no parameters, nothing to train)."""
    load_plugins()
    return [n for n, entry in _REGISTRY.items() if entry.cls.trivial]


def coordinates(name: str) -> tuple[str, ...]:
    """The coordinate settings ("velocity", "momentum") that model ``name`` accepts."""
    load_plugins()
    if name not in _REGISTRY:
        raise ValueError(f"unknown model {name!r}; allowed: {available()}")
    needs = _REGISTRY[name].needs
    return (_V, _P) if needs is None else (needs,)


def make(
    name: str,
    scene: Scene,
    *,
    key,
    width: int = 256,
    depth: int = 2,
    activation: str | None = None,
    dtype: str = "float32",
    dissipation: bool | None = None,
    **options,
):
    """Build the model ``name`` for ``scene``.

    ``activation`` None takes the model's default (softplus for lnn, as in the LNN seed; tanh
    otherwise). ``dissipation`` None follows ``scene.damped`` for the structured models (hnn,
    hnn_so, lnn, vin, vin_implicit); False forces the plain variant; free models ignore it.
    """
    load_plugins()
    if name not in _REGISTRY:
        close = difflib.get_close_matches(str(name), list(_REGISTRY), n=1)
        hint = f" (closest: {close[0]!r})" if close else ""
        raise ValueError(f"unknown model {name!r}{hint}; allowed: {available()}")
    builder, allowed, structured, needs, default_activation = _REGISTRY[name][1:]
    if not isinstance(scene, Scene):
        raise ValueError(f"scene must be a models.Scene, got {type(scene).__name__}")
    for field, value in (("width", width), ("depth", depth)):
        if isinstance(value, bool) or not isinstance(value, int) or value < 1:
            raise ValueError(f"{field} must be an int >= 1, got {value!r}")
    activation = default_activation if activation is None else activation
    if activation not in ACTIVATIONS:
        raise ValueError(f"activation must be one of {sorted(ACTIVATIONS)}, got {activation!r}")
    if dtype not in DTYPES:
        raise ValueError(f"dtype must be one of {DTYPES}, got {dtype!r}")
    unknown = sorted(set(options) - set(allowed))
    if unknown:
        raise ValueError(
            f"unknown option(s) {unknown} for model {name!r}; allowed: {sorted(allowed)}"
        )
    options = {k: allowed[k](v) for k, v in options.items()}
    if dissipation is not None and not isinstance(dissipation, bool):
        raise ValueError(f"dissipation must be None, True or False, got {dissipation!r}")
    if needs == _V and scene.canonical:
        raise ValueError(f"model {name!r} needs velocity coordinates (Scene.canonical=False)")
    if needs == _P and not scene.canonical:
        raise ValueError(f"model {name!r} needs momentum coordinates (Scene.canonical=True)")
    cls = _REGISTRY[name].cls
    if scene.n_controls and not (getattr(cls, "takes_controls", False) or cls.trivial):
        takers = [n for n, e in _REGISTRY.items() if getattr(e.cls, "takes_controls", False)]
        raise ValueError(
            f"model {name!r} has no part that reads a control input (Scene.n_controls="
            f"{scene.n_controls}); models that do: {', '.join(takers)}"
        )
    dissipation = (scene.damped if dissipation is None else dissipation) and structured
    return builder(
        scene, width, depth, activation, dtype, key=key, dissipation=dissipation, **options
    )


def n_parameters(model) -> int:
    """The number of trainable scalars of a model."""
    leaves = jax.tree_util.tree_leaves(eqx.filter(model, eqx.is_inexact_array))
    return int(sum(x.size for x in leaves))
