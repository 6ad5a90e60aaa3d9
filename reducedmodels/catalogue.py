"""The model catalogue: every model family registers here once, and every command asks it.

A model id names a family, optionally its resolution and options::

    FAMILY[:RESOLUTION][[OPTION,OPTION=VALUE,...]]

e.g. ``beam:100``, ``beam:100[shear]``, ``dcmm:2[frame=follower]``,
``continuum:1[law=neo-hookean,plane=strain]``, ``prbm``. A family without a
resolution takes none; a family with one uses its default when none is given
(``beam`` is ``beam:20``). An option given by its bare name takes its "bare"
value (``shear`` is ``shear=true``). The *canonical* id lists the options that
differ from their defaults, sorted by name (``beam:100[shear=false]`` is
``beam:100``), and the canonical id is what every output (JSON ``model``,
tables, cache keys) carries.

A :class:`Family` holds everything the commands need to know about a model:
its id syntax (:class:`Resolution`), its :class:`Option` set, a runner that
traces a load case (imports its code lazily, so ``flexval info`` never loads
a solver) and its capabilities (:data:`FIELDS`, :data:`ARCLENGTH`,
:data:`LINEAR`, :data:`REFERENCE`). Adding a family is one module that calls
:func:`register`. The built-in ones are named in :data:`BUILT_IN_FAMILIES`
(the reduced models in :mod:`flexval.reducedmodels.families`, the continuum
in :mod:`flexval.validation.continuum.family`) and imported the first time
the catalogue is asked for a family; an installed package's families come
through the entry-point group ``flexval.families`` (:func:`load_plugins`),
loaded the first time an id names a family that is not registered.

Bad ids raise :class:`geometry.SceneError` naming the source, the field and
the text (the CLI turns it into exit code 2).
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import Any

from flexval.geometry import SceneError
from flexval.geometry.errors import COMMAND_LINE

#: capability: writes stress fields (VTU files, PNG renderings) of the deformed flexures
FIELDS = "fields"
#: capability: ``Family.system`` builds a System that arc-length continuation can trace
ARCLENGTH = "arclength"
#: capability: a linear model (its path is proportional to the load; no limit points)
LINEAR = "linear"
#: capability: a reference model: its default resolution is the reports' reference, its
#: coarser resolutions join the runtime-versus-error study and it is timed once (seconds a run)
REFERENCE = "reference"
#: capability: traces a load case that prescribes a motion (``Mechanism.drive``: the family
#: joins :func:`flexval.reducedmodels.core.drives.constraint_connectors` to its connectors)
DISPLACEMENT = "displacement"
CAPABILITIES = frozenset({FIELDS, ARCLENGTH, LINEAR, REFERENCE, DISPLACEMENT})

_ID_RE = re.compile(
    r"^(?P<family>[A-Za-z][\w-]*)(?::(?P<res>[^\[\]]*))?"
    r"(?:\[(?P<opts>[^\[\]]*)\])?$"
)


@dataclass(frozen=True)
class Resolution:
    """The integer after the colon of a model id.

    Parameters
    ----------
    name : str
        Its name in the syntax, e.g. ``N`` or ``LEVEL``.
    meaning : str
        What it counts (with its unit), for help texts.
    default, low, high : int
        Default when omitted and the allowed range (inclusive).
    doubling : bool
        How a convergence study refines it: True when the element size is
        inversely proportional to it (N doubles each step, refinement ratio
        N2 / N1); False when each step of one halves the element size
        (refinement ratio 2 per step).
    study : tuple of int
        Default (first, last) resolution of ``flexval converge``.
    """

    name: str
    meaning: str
    default: int
    low: int
    high: int
    doubling: bool
    study: tuple[int, int]

    def ratio(self, coarse: int, fine: int) -> float:
        """Refinement ratio (element size of ``coarse`` / of ``fine``)."""
        return fine / coarse if self.doubling else 2.0 ** (fine - coarse)

    def series(self, first: int, last: int) -> list[int]:
        """The resolutions of a study from ``first`` up to at most ``last``."""
        if not self.doubling:
            return list(range(first, last + 1))
        out = [first]
        while out[-1] * 2 <= last:
            out.append(out[-1] * 2)
        return out


@dataclass(frozen=True)
class Option:
    """One option of a family: ``name=value`` inside the id's brackets.

    Parameters
    ----------
    name : str
        Name in the id.
    doc : str
        What it does (for ``flexval models``, the documentation and help texts).
    values : tuple of (str, object)
        Allowed text values and the Python value each passes to the runner.
    default : str
        Text value when the option is not given (never printed in an id).
    bare : str, optional
        Text value meant by the bare name (``shear`` for ``shear=true``).
    keyword : str, optional
        Keyword argument of the runner/connector (default: ``name``).
    """

    name: str
    doc: str
    values: tuple[tuple[str, Any], ...]
    default: str
    bare: str | None = None
    keyword: str | None = None

    @classmethod
    def flag(cls, name: str, doc: str, keyword: str | None = None) -> Option:
        """A boolean option, off by default, switched on by its bare name."""
        return cls(name, doc, (("false", False), ("true", True)), "false", "true", keyword)

    @classmethod
    def choice(
        cls, name: str, doc: str, choices: tuple[str, ...], default: str, keyword: str | None = None
    ) -> Option:
        """An option taking one of ``choices`` (passed on as the text itself)."""
        return cls(name, doc, tuple((c, c) for c in choices), default, None, keyword)

    @property
    def allowed(self) -> tuple[str, ...]:
        """The allowed text values."""
        return tuple(text for text, _ in self.values)

    def python(self, text: str) -> Any:
        """The Python value of the text value ``text``."""
        return dict(self.values)[text]

    def canonical(self, text: str) -> str:
        """How ``name=text`` is printed in a canonical id."""
        return self.name if text == self.bare else f"{self.name}={text}"

    def describe(self) -> str:
        """``name=a|b (default a): doc``."""
        bare = f"; bare '{self.name}' = {self.name}={self.bare}" if self.bare else ""
        return f"{self.name}={'|'.join(self.allowed)} (default {self.default}{bare}): {self.doc}"


@dataclass(frozen=True)
class Cost:
    """What one load path of a model is estimated to take, before it is built.

    Attributes
    ----------
    bytes : float
        Peak resident memory of the process running it, bytes.
    seconds : float
        Wall time, s.
    size : str
        What the estimate grows with, for messages (e.g. ``"182,682 unknowns"``).
    """

    bytes: float
    seconds: float
    size: str


@dataclass(frozen=True)
class Family:
    """A model family: id syntax, options, how to run it and what it can do.

    Parameters
    ----------
    name : str
        The id's family name.
    summary : str
        One line: what the model is.
    run : callable
        ``run(scene_name, mechanism, spec, case, levels, record_poses,
        record_shapes, **extra) -> reducedmodels.LoadPath``: traces ``case``
        (raises ``reducedmodels.SolverError`` when it cannot reach full load).
        It imports the model's code when called. ``extra`` are the output
        keywords of the capabilities (``vtu_dir``, ``png`` for
        :data:`FIELDS`).
    resolution : Resolution, optional
        None for families that take no resolution.
    options : tuple of Option
    capabilities : frozenset of str
        Some of :data:`CAPABILITIES`.
    system : callable, optional
        ``system(mechanism, spec, settings) -> reducedmodels.System`` (for
        :data:`ARCLENGTH`).
    cost : callable, optional
        ``cost(mechanism, spec, levels) -> Cost``: the peak memory and the time
        of one load path of ``levels`` load levels, estimated from the
        mechanism and the spec without building anything (None: a family
        whose paths are small and quick whatever the resolution).
    connectors : callable, optional
        ``connectors(mechanism, spec, **options) -> list of Connector``: the
        connectors ``system`` joins, without the System (a batch of copies,
        :mod:`flexval.reducedmodels.core.batch`, numbers them once for all
        copies). None: a batch builds each copy's System.
    exclusive : tuple of (str, str)
        Pairs of options (a, b) where b means nothing once a is set: an id
        giving a a value other than its default and naming b is refused.
    load : callable, optional
        ``load(spec)``: imports the code a run of ``spec`` executes and loads
        its compiled kernels, the per-process costs a first run pays (a
        sweep's workers are forked with them paid:
        :mod:`flexval.validation.sweep.preload`). None: nothing to load ahead.
    """

    name: str
    summary: str
    run: Callable[..., Any]
    resolution: Resolution | None = None
    options: tuple[Option, ...] = ()
    capabilities: frozenset[str] = frozenset()
    system: Callable[..., Any] | None = None
    cost: Callable[..., Cost] | None = None
    connectors: Callable[..., Any] | None = None
    exclusive: tuple[tuple[str, str], ...] = ()
    load: Callable[[ModelSpec], None] | None = None

    def __post_init__(self) -> None:
        unknown = set(self.capabilities) - CAPABILITIES
        if unknown:
            raise ValueError(
                f"family {self.name!r}: unknown capabilities {sorted(unknown)}; "
                f"expected some of {sorted(CAPABILITIES)}"
            )
        if ARCLENGTH in self.capabilities and self.system is None:
            raise ValueError(f"family {self.name!r}: capability {ARCLENGTH!r} needs `system`")

    @property
    def syntax(self) -> str:
        """E.g. ``beam[:N][[options]]``."""
        res = f"[:{self.resolution.name}]" if self.resolution else ""
        return self.name + res + ("[[options]]" if self.options else "")

    def has(self, capability: str) -> bool:
        """Whether the family has ``capability``."""
        return capability in self.capabilities

    def trace(self, mechanism, spec: ModelSpec, case, **keywords) -> Any:
        """``run`` of ``case`` on ``mechanism`` as the case loads it (its drive, if it
        prescribes a motion: :meth:`flexval.geometry.Mechanism.driven_by`).

        Raises
        ------
        SceneError
            If ``case`` prescribes a motion and the family cannot trace one (no
            :data:`DISPLACEMENT` capability).
        """
        return self.run(self.loaded(mechanism, case), spec, case, **keywords)

    def loaded(self, mechanism, case):
        """``mechanism`` as ``case`` loads it, for this family's ``run`` or ``system``: with
        the case's drive where it prescribes a motion
        (:meth:`flexval.geometry.Mechanism.driven_by`).

        Raises
        ------
        SceneError
            If ``case`` prescribes a motion and the family cannot trace one (no
            :data:`DISPLACEMENT` capability).
        """
        if case.drive is not None and not self.has(DISPLACEMENT):
            raise SceneError(
                mechanism.source,
                f"load_cases.{case.name}.kind",
                "displacement",
                f"model family {self.name!r} does not trace a prescribed motion "
                "(displacement control); use a force or a moment",
            )
        return mechanism.driven_by(case)

    def option(self, name: str) -> Option | None:
        """The option called ``name``, or None."""
        return next((o for o in self.options if o.name == name), None)

    def spec(self, resolution: int | None = None, **options: str) -> ModelSpec:
        """A checked :class:`ModelSpec` of this family (options as text values)."""
        text = self.name if resolution is None else f"{self.name}:{resolution}"
        if options:
            text += "[" + ",".join(f"{k}={v}" for k, v in options.items()) + "]"
        return parse_model(text, "<python>", "model")


@dataclass(frozen=True)
class ModelSpec:
    """A requested model: family name, resolution and canonical options.

    Build it with :func:`parse_model` (which checks it); ``options`` holds
    (name, text value) pairs of the options that differ from their
    defaults, sorted by name.
    """

    family: str
    resolution: int | None = None
    options: tuple[tuple[str, str], ...] = field(default=())

    @property
    def id(self) -> str:
        """Canonical text form, e.g. ``beam:100`` or ``dcmm:2[frame=follower]``."""
        text = self.family if self.resolution is None else f"{self.family}:{self.resolution}"
        if self.options:
            fam = family(self.family)
            text += "[" + ",".join(fam.option(k).canonical(v) for k, v in self.options) + "]"
        return text

    def __str__(self) -> str:
        return self.id

    @property
    def model_family(self) -> Family:
        """The registered :class:`Family` of this spec."""
        return family(self.family)

    @property
    def kwargs(self) -> dict[str, Any]:
        """The options as Python keyword arguments of the runner/connector."""
        fam = family(self.family)
        out = {}
        for name, text in self.options:
            opt = fam.option(name)
            out[opt.keyword or opt.name] = opt.python(text)
        return out

    def with_resolution(self, resolution: int) -> ModelSpec:
        """The same model and options at another resolution (checked)."""
        return family(self.family).spec(resolution, **dict(self.options))

    def with_options(self, **options: str) -> ModelSpec:
        """The same model with ``options`` (text values) set or replaced (checked)."""
        return family(self.family).spec(self.resolution, **{**dict(self.options), **options})


BUILT_IN_FAMILIES = {
    "beam": "flexval.reducedmodels.families",
    "prbm": "flexval.reducedmodels.families",
    "dcmm": "flexval.reducedmodels.families",
    "ee": "flexval.reducedmodels.families",
    "continuum": "flexval.validation.continuum.family",
}
"""Every built-in family and the module that declares it, imported the first time the
catalogue is asked for a family (registration by name: importing a package registers
nothing). Declaring a family imports none of its solver code."""

_FAMILIES: dict[str, Family] = {}
_PLUGIN_OF: dict[str, str] = {}
"""Family name -> the distribution package whose entry point registered it."""
_LOADING: list[str] = []
"""The package whose entry point is being loaded (:func:`load_plugins`)."""
_loaded = {"built-in": False, "plug-ins": False}


def _load_built_ins() -> None:
    """Import the modules of :data:`BUILT_IN_FAMILIES` (once per process)."""
    if _loaded["built-in"]:
        return
    _loaded["built-in"] = True
    from importlib import import_module

    for module in dict.fromkeys(BUILT_IN_FAMILIES.values()):
        import_module(module)


def register(fam: Family) -> Family:
    """Add ``fam`` to the catalogue (re-registering the same name replaces it).

    While a plug-in package's entry point is loaded (:func:`load_plugins`), a
    name that is already registered is refused instead: a plug-in never
    replaces a built-in family or another package's.

    Raises
    ------
    SceneError
        A plug-in registering a name already taken (naming the package).
    """
    if _LOADING:
        package = _LOADING[-1]
        if fam.name in _FAMILIES and _FAMILIES[fam.name] is not fam:
            owner = _PLUGIN_OF.get(fam.name)
            taken = f"the family of plug-in package {owner!r}" if owner else "a built-in family"
            raise SceneError(
                f"<plug-in package {package}>",
                "flexval.families",
                fam.name,
                f"the family name clashes with {taken}; rename the plug-in's family",
            )
        _PLUGIN_OF[fam.name] = package
    _FAMILIES[fam.name] = fam
    return fam


def _register_returned(result: object) -> None:
    """Register what a plug-in entry point's callable returned (a Family, several, or None)."""
    if result is None:
        return
    fams = [result] if isinstance(result, Family) else result
    if not isinstance(fams, Iterable) or not all(isinstance(f, Family) for f in fams):
        raise TypeError(
            f"returned {type(result).__name__}, expected Family, a list of them or None"
        )
    for fam in fams:
        register(fam)


def load_plugins() -> tuple[str, ...]:
    """Register every installed plug-in's families (once per process).

    The entry points of the group ``flexval.families``
    (:mod:`flexval.reducedmodels.plugins`): a module whose import calls
    :func:`register`, or a callable that does so or returns a :class:`Family`
    (or a list of them).

    Returns
    -------
    tuple of str
        The family names the plug-ins registered (empty on later calls).

    Raises
    ------
    SceneError
        A plug-in that fails to load or clashes with a registered family name;
        the source names the distribution package.
    """
    if _loaded["plug-ins"]:
        return ()
    _loaded["plug-ins"] = True
    _load_built_ins()
    from .plugins import installed, run_entry_point

    before = set(_FAMILIES)
    for package, ep in installed():
        _LOADING.append(package)
        try:
            run_entry_point(package, ep, _register_returned)
        finally:
            _LOADING.pop()
    return tuple(name for name in _FAMILIES if name not in before)


def plugin_of(name: str) -> str | None:
    """The distribution package that registered the family ``name`` as a plug-in (None:
    registered by flexval or by a direct :func:`register` call)."""
    return _PLUGIN_OF.get(name)


def unregister(name: str) -> None:
    """Remove the family ``name`` (e.g. a test's toy family)."""
    _FAMILIES.pop(name, None)
    _PLUGIN_OF.pop(name, None)


def families() -> tuple[Family, ...]:
    """Every registered family, the built-in ones first, in registration order."""
    _load_built_ins()
    return tuple(_FAMILIES.values())


def family(name: str) -> Family:
    """The registered family ``name`` (KeyError if there is none)."""
    _load_built_ins()
    return _FAMILIES[name]


def expected_ids() -> str:
    """Human-readable list of the accepted id forms, e.g. for error messages and help."""
    return ", ".join(f.syntax for f in families())


def _parse_options(
    fam: Family, text: str, fail: Callable[[str], None]
) -> tuple[tuple[str, str], ...]:
    given: dict[str, str] = {}
    for item in (t.strip() for t in text.split(",")):
        name, eq, value = (s.strip() for s in item.partition("="))
        opt = fam.option(name)
        if opt is None:
            allowed = "; ".join(o.describe() for o in fam.options) or "none"
            fail(f"unknown option {name!r} of '{fam.name}'; allowed: {allowed}")
        if not eq:
            if opt.bare is None:
                fail(
                    f"option {name!r} of '{fam.name}' needs a value, one of "
                    f"{', '.join(opt.allowed)}"
                )
            value = opt.bare
        if value not in opt.allowed:
            fail(
                f"option {name!r} of '{fam.name}' must be one of {', '.join(opt.allowed)}, "
                f"got {value!r}"
            )
        if name in given:
            fail(f"option {name!r} given twice")
        given[name] = value
    for a, b in fam.exclusive:
        if given.get(a, fam.option(a).default) != fam.option(a).default and b in given:
            fail(f"option {b!r} of '{fam.name}' means nothing with {a!r}; leave it out")
    return tuple(sorted((k, v) for k, v in given.items() if v != fam.option(k).default))


def parse_model(text: str, source: str = COMMAND_LINE, field: str = "model") -> ModelSpec:
    """Parse a model id (see the module docstring) into a checked, canonical ModelSpec.

    Raises
    ------
    SceneError
        Naming ``source``, ``field`` and ``text``: unknown family, bad or
        out-of-range resolution, unknown option or value.
    """

    def fail(reason: str) -> None:
        raise SceneError(source, field, text, reason)

    if not isinstance(text, str):
        fail(f"expected a model id string: {expected_ids()}")
    _load_built_ins()
    m = _ID_RE.match(text.strip())
    if m and m.group("family") not in _FAMILIES:
        load_plugins()  # entry points are looked up only for unknown names
    if not m or m.group("family") not in _FAMILIES:
        fail(f"expected {expected_ids()}")
    fam = _FAMILIES[m.group("family")]
    res_text, opts = m.group("res"), m.group("opts")
    res = fam.resolution
    if res is None:
        if res_text is not None:
            fail(f"'{fam.name}' takes no resolution")
        n = None
    elif res_text is None:
        n = res.default
    else:
        if not re.fullmatch(r"\d+", res_text.strip()):
            fail(f"the {res.name} of '{fam.name}' ({res.meaning}) must be an integer")
        n = int(res_text)
        if not res.low <= n <= res.high:
            fail(
                f"the {res.name} of '{fam.name}' ({res.meaning}) must be between {res.low} "
                f"and {res.high}"
            )
    options = _parse_options(fam, opts, fail) if opts is not None and opts.strip() else ()
    return ModelSpec(fam.name, n, options)
