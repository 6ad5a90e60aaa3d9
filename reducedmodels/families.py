"""The reduced model families of the paper, registered in the model catalogue.

``beam:N``, ``dcmm:N``, ``prbm`` and ``ee`` (see :mod:`flexval.reducedmodels.catalogue`
for the id syntax). Registering them imports no solver code: the multibody
core (scipy) is imported when a model of a family runs or builds a system,
each connector module only when a model of its family is built, so commands
that only read the catalogue (``flexval --help``, ``flexval info``) start fast.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from .catalogue import (
    ARCLENGTH,
    DISPLACEMENT,
    LINEAR,
    Family,
    ModelSpec,
    Option,
    Resolution,
    register,
)

if TYPE_CHECKING:
    from flexval.geometry import Flexure, LoadCase, Mechanism

    from .core.settings import SolverSettings
    from .core.system import System

#: largest N of ``beam:N`` and ``dcmm:N`` (a guard against typos, far beyond any use)
MAX_ELEMENTS = 100_000

PLATE = Option.flag(
    "plate",
    "wide flexures: the material's plane-strain constants E/(1-nu^2) and nu/(1-nu) "
    "(anticlastic curvature suppressed; the counterpart of continuum[plane=strain])",
)

WIDTH = Option.flag(
    "width",
    "flexures of finite depth b: each flexure's bending modulus E r(beta) from the "
    "anticlastic curvature of its section, beta = b^2/(R h) (Searle's parameter, tending "
    "to plate's 1/(1-nu^2) as beta grows); a straight uniform leaf's from the plate "
    "stiffening its clamps give it (fitted to the 3D solid over b/L); shear modulus "
    "kept; excludes plate",
)

EB = Option.flag(
    "eb",
    "notch hinges by plain Euler-Bernoulli beam theory (the integral of ds/EI, no shear): "
    "without the calibrated 2D correction the default takes from the continuum",
)

WIDTH_EXCLUDES = (("width", "plate"),)
"""``plate`` is ``width``'s limit of a flexure much deeper than sqrt(R h): an id gives one."""

FRAME = Option.choice(
    "frame",
    "DCMM measuring frame: each element's relative displacement is measured in the "
    "displaced frame of its leading body (the paper's text) or of the following one",
    ("leader", "follower"),
    "leader",
)


def _beam(flexure: Flexure, mechanism: Mechanism, spec: ModelSpec, **options):
    from .beam.elements import BeamConnector

    return BeamConnector(flexure, mechanism, spec.resolution, **options)


def _dcmm(flexure: Flexure, mechanism: Mechanism, spec: ModelSpec, **options):
    from .dcmm.connector import dcmm_connector

    return dcmm_connector(flexure, mechanism, spec.resolution, **options)


def _ee(flexure: Flexure, mechanism: Mechanism, spec: ModelSpec, **options):
    from .dcmm.connector import DcmmConnector

    return DcmmConnector(flexure, mechanism, 1, **options)


def _prbm(flexure: Flexure, mechanism: Mechanism, spec: ModelSpec, **options):
    from .prbm.connector import prbm_connector

    return prbm_connector(flexure, mechanism, **options)


def _load_core() -> None:
    """Import the multibody core (scipy.linalg with it) and the compiled kernels' modules
    (numba with them), and cap the BLAS threads.

    All are per-process costs, like importing scipy, not a model's: left
    inside the timed build, they would make a process's first ``dcmm:1``,
    ``prbm`` or ``ee`` run print several times the time of its second run of
    the same path. The kernels' machine code is compiled, or loaded from the
    on-disk cache, where a kernel is first called, on a clock that leaves it
    out (:mod:`flexval.reducedmodels.kernels.clock`): a run compiles only the
    kernels it uses.
    """
    from . import models  # noqa: F401  (the core, imported ahead of the timed build)
    from .core.threads import limit_threads
    from .kernels import (  # noqa: F401  (numba and the kernels' dispatchers)
        bandkernel,
        beamkernel,
        chainkernel,
        dcmmkernel,
        ldlkernel,
        orderkernel,
        prbmkernel,
        stabilitykernel,
        stresskernel,
    )
    from .kernels.jit import initialise

    limit_threads()
    initialise()


def _warm_newton_kernels() -> None:
    """Every compiled kernel that orders a System's tangent, factorises a batch's blocks,
    counts a band's negative pivots and stacks a batch's stresses (every family traced by
    Newton), compiled or loaded now."""
    from .kernels import ldlkernel, orderkernel, stabilitykernel, stresskernel

    orderkernel.warm_up()
    ldlkernel.warm_up()
    stabilitykernel.warm_up()
    stresskernel.warm_up()


def _load_ee(spec: ModelSpec) -> None:
    """``Family.load`` of ``ee``: the core and every kernel of the DCMM connectors."""
    from .dcmm.connector import CHAIN_HALF_BANDWIDTH
    from .kernels import bandkernel, chainkernel, dcmmkernel

    _load_core()
    dcmmkernel.warm_up()
    bandkernel.warm_up(CHAIN_HALF_BANDWIDTH)
    chainkernel.warm_up()


def _load_dcmm(spec: ModelSpec) -> None:
    """``Family.load`` of ``dcmm:N``: :func:`_load_ee` and the Newton kernels."""
    _load_ee(spec)
    _warm_newton_kernels()


def _load_prbm(spec: ModelSpec) -> None:
    """``Family.load`` of ``prbm``: the core, its kernels and the Newton kernels."""
    from .kernels import prbmkernel
    from .prbm import connector  # noqa: F401  (its code)

    _load_core()
    prbmkernel.warm_up()
    _warm_newton_kernels()


def _load_beams(spec: ModelSpec) -> None:
    """``Family.load`` of ``beam:N``: the core, the beam, chain and band kernels and the
    Newton kernels."""
    from .beam.elements import CHAIN_HALF_BANDWIDTH
    from .kernels import bandkernel, beamkernel, chainkernel

    _load_core()
    beamkernel.warm_up()
    chainkernel.warm_up()
    bandkernel.warm_up(CHAIN_HALF_BANDWIDTH)
    _warm_newton_kernels()


def _traced_by_newton(code: str) -> Callable[..., Any]:
    """``Family.run`` of a family traced by Newton whose connectors live in the module
    ``code`` (relative to this package): that module and the core loaded (outside the
    path's time), then :func:`flexval.reducedmodels.models.trace_nonlinear`."""

    def run(mechanism: Mechanism, spec: ModelSpec, *args, **kwargs):
        importlib.import_module(code, __package__)
        _load_core()
        from .models import trace_nonlinear

        return trace_nonlinear(mechanism, spec, *args, **kwargs)

    return run


def _trace_ee(
    mechanism: Mechanism,
    spec: ModelSpec,
    case: LoadCase,
    levels: int | None = None,
    scene: str = "",
    record_poses: bool = False,
    record_shapes: bool = False,
    record_reactions: bool = False,
    **options,
):
    """The linear response of dcmm:1's connectors, without a System (wall time includes the build).

    :func:`flexval.reducedmodels.models.linear_response` of the family's connectors:
    the numbers of :func:`flexval.reducedmodels.models.trace_linear` on its System
    (tests/test_joints.py), without the index maps and solver state a System
    builds for Newton iterations. ``record_poses`` and ``record_shapes`` record
    the linearised poses and shapes; ``record_reactions`` is accepted for a
    uniform runner signature and ignored.
    """
    from .dcmm import connector  # noqa: F401  (its connectors' code, ahead of the clock)

    _load_core()
    from .kernels.clock import path_clock
    from .models import flexure_connectors, linear_response

    t0 = path_clock()
    connectors = flexure_connectors(mechanism, spec, _ee, {**spec.kwargs, **options})
    lp = linear_response(
        mechanism,
        connectors,
        case,
        levels,
        spec.id,
        scene,
        record_poses=record_poses,
        record_shapes=record_shapes,
    )
    lp.seconds = path_clock() - t0
    return lp


def _connectors_of(make):
    """``Family.connectors`` of a family whose flexures are ``make`` connectors."""

    def connectors(mechanism: Mechanism, spec: ModelSpec, **options) -> list:
        from .models import flexure_connectors

        return flexure_connectors(mechanism, spec, make, options)

    return connectors


def _system_of(make):
    """``Family.system`` of a family whose flexures are ``make`` connectors."""

    def system(
        mechanism: Mechanism, spec: ModelSpec, settings: SolverSettings | None = None, **options
    ) -> System:
        from .models import connector_system

        return connector_system(mechanism, spec, make, settings, options)

    return system


BEAM = register(
    Family(
        "beam",
        "geometrically exact corotational beam elements (Euler-Bernoulli, or Timoshenko "
        "with the option shear); beam:100 and beam:20 are the paper's FEM100 and FEM20",
        _traced_by_newton(".beam.elements"),
        Resolution("N", "beam elements per flexure", 20, 1, MAX_ELEMENTS, True, (5, 320)),
        (
            Option.flag("shear", "Timoshenko beams (shear deformation of the rectangular section)"),
            PLATE,
            WIDTH,
            EB,
        ),
        frozenset({ARCLENGTH, DISPLACEMENT}),
        _system_of(_beam),
        connectors=_connectors_of(_beam),
        exclusive=WIDTH_EXCLUDES,
        load=_load_beams,
    )
)

PRBM = register(
    Family(
        "prbm",
        "symmetric 3R pseudo-rigid-body chain per flexure, exact in the linear limit",
        _traced_by_newton(".prbm.connector"),
        None,
        (PLATE, WIDTH, EB),
        frozenset({ARCLENGTH, DISPLACEMENT}),
        _system_of(_prbm),
        connectors=_connectors_of(_prbm),
        exclusive=WIDTH_EXCLUDES,
        load=_load_prbm,
    )
)

DCMM = register(
    Family(
        "dcmm",
        "Displaced Compliance Matrix Method: each arc cut into N sub-arcs, each a diagonal "
        "compliance at its centre of elasticity",
        _traced_by_newton(".dcmm.connector"),
        Resolution("N", "sub-arcs per flexure", 1, 1, MAX_ELEMENTS, True, (1, 8)),
        (FRAME, PLATE, WIDTH, EB),
        frozenset({ARCLENGTH, DISPLACEMENT}),
        _system_of(_dcmm),
        connectors=_connectors_of(_dcmm),
        exclusive=WIDTH_EXCLUDES,
        load=_load_dcmm,
    )
)

EE = register(
    Family(
        "ee",
        "linear ellipse-of-elasticity prediction (the small-load limit of dcmm:1)",
        _trace_ee,
        None,
        (PLATE, WIDTH, EB),
        frozenset({LINEAR, DISPLACEMENT}),
        _system_of(_ee),
        connectors=_connectors_of(_ee),
        exclusive=WIDTH_EXCLUDES,
        load=_load_ee,
    )
)
