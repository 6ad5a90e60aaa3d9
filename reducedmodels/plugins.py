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

Loading is lazy: reading the installed packages' metadata costs a few
milliseconds, so :func:`load_plugins` runs only when a model id names a
family that is not registered (:func:`~flexval.reducedmodels.catalogue.parse_model`)
or when every family is listed (``flexval models``), and then once per
process. A plug-in whose entry point fails to import or run (whatever it
raises, ``SystemExit`` and ``KeyboardInterrupt`` included: a plug-in that
exits never ends a command as a success), or whose family name is already
registered (a built-in family or another package's), is refused with a
:class:`geometry.SceneError` naming the package (the CLI's exit code 2).
"""

from __future__ import annotations

from collections.abc import Iterable
from types import ModuleType

from flexval.geometry import SceneError

from . import catalogue
from .catalogue import Family

GROUP = "flexval.families"
"""The entry-point group plug-in packages register their families under."""

_loaded = False


def _register_returned(result: object) -> None:
    """Register what an entry point's callable returned (a Family, several, or None)."""
    if result is None:
        return
    fams = [result] if isinstance(result, Family) else result
    if not isinstance(fams, Iterable) or not all(isinstance(f, Family) for f in fams):
        raise TypeError(
            f"returned {type(result).__name__}, expected Family, a list of them or None"
        )
    for fam in fams:
        catalogue.register(fam)


def load_plugins() -> tuple[str, ...]:
    """Load every installed plug-in's families (once per process).

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
    global _loaded
    if _loaded:
        return ()
    _loaded = True
    from importlib.metadata import entry_points

    before = set(f.name for f in catalogue.families())
    for ep in sorted(entry_points(group=GROUP), key=lambda e: (e.value, e.name)):
        package = ep.dist.name if ep.dist is not None else ep.value
        catalogue._LOADING.append(package)
        try:
            loaded = ep.load()
            if not isinstance(loaded, ModuleType):
                if not callable(loaded):
                    raise TypeError(
                        f"{ep.value} is a {type(loaded).__name__}, not a module or callable"
                    )
                _register_returned(loaded())
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
        finally:
            catalogue._LOADING.pop()
    return tuple(f.name for f in catalogue.families() if f.name not in before)
