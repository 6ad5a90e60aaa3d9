"""Model families from installed packages: the entry-point group ``flexval.families``.

A package adds families without touching flexval by declaring, in its
``pyproject.toml``::

    [project.entry-points."flexval.families"]
    my-model = "my_package.family"            # a module that calls register(Family(...))
    # or  my-model = "my_package.family:families"   a callable

The entry point is a module whose import calls
:func:`flexval.reducedmodels.catalogue.register`, or a callable that does so
or returns a :class:`~flexval.reducedmodels.catalogue.Family` (or a list of
them), which is then registered.

This module reads and runs the entry points; the catalogue
(:func:`flexval.reducedmodels.catalogue.load_plugins`) registers what they
give. Loading is lazy: reading the installed packages' metadata costs a few
milliseconds, so it runs only when a model id names a
family that is not registered (:func:`~flexval.reducedmodels.catalogue.parse_model`)
or when every family is listed (``flexval models``), and then once per
process. A plug-in whose entry point fails to import or run (whatever it
raises, ``SystemExit`` and ``KeyboardInterrupt`` included: a plug-in that
exits never ends a command as a success), or whose family name is already
registered (a built-in family or another package's), is refused with a
:class:`geometry.SceneError` naming the package (the CLI's exit code 2).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from importlib.metadata import EntryPoint
from types import ModuleType

from flexval.geometry import SceneError

GROUP = "flexval.families"
"""The entry-point group plug-in packages register their families under."""


def installed() -> Iterator[tuple[str, EntryPoint]]:
    """Every installed entry point of :data:`GROUP` with its distribution package's name,
    in a fixed order (by value, then name)."""
    from importlib.metadata import entry_points

    for ep in sorted(entry_points(group=GROUP), key=lambda e: (e.value, e.name)):
        yield (ep.dist.name if ep.dist is not None else ep.value), ep


def run_entry_point(package: str, ep: EntryPoint, accept: Callable[[object], None]) -> None:
    """Load ``ep`` (a module, or a callable that is then called) and hand what a callable
    returns to ``accept``.

    Raises
    ------
    SceneError
        When anything fails (``SystemExit`` and ``KeyboardInterrupt`` from the
        plug-in included), naming ``package``; a ``SceneError`` raised inside
        (a clashing family name) passes through as it is.
    """
    try:
        loaded = ep.load()
        if not isinstance(loaded, ModuleType):
            if not callable(loaded):
                raise TypeError(
                    f"{ep.value} is a {type(loaded).__name__}, not a module or callable"
                )
            accept(loaded())
    except SceneError:
        raise
    except (Exception, SystemExit, KeyboardInterrupt) as exc:
        if isinstance(exc, KeyboardInterrupt) and type(exc) is not KeyboardInterrupt:
            raise  # a signal the command turned into its own interruption: not the plug-in's
        raise SceneError(
            f"<plug-in package {package}>",
            f"{GROUP}.{ep.name}",
            ep.value,
            f"the plug-in failed to load: {type(exc).__name__}: {exc}",
        ) from None
