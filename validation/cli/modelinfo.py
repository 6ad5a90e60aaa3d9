"""``flexval models``: every registered model family, read from the catalogue.

Nothing here names a family: the listing is built from
:func:`flexval.reducedmodels.catalogue.families`, so a family registered by a
plug-in module appears like the built-in ones; the CLI loads the installed
plug-in packages' families first (:func:`flexval.reducedmodels.catalogue.load_plugins`),
and each one's package is named. Only the catalogue is imported, no solver.
"""

from __future__ import annotations

import textwrap

from flexval.reducedmodels.catalogue import (
    ARCLENGTH,
    CAPABILITIES,
    DISPLACEMENT,
    FIELDS,
    LINEAR,
    REFERENCE,
    Family,
    Option,
    families,
    plugin_of,
)

from ..report.tables import Column, text_table

CAPABILITY_DOCS = {
    ARCLENGTH: "traced through limit points by `flexval run --arclength`",
    DISPLACEMENT: "traces a load case that prescribes a motion (displacement control)",
    FIELDS: "writes stress fields of the deformed flexures (VTU, PNG)",
    LINEAR: "linear response: the path is proportional to the load, no limit points",
    REFERENCE: "the reference of reports and benchmarks (its default resolution)",
}
"""One line per capability of :data:`flexval.reducedmodels.catalogue.CAPABILITIES`."""

ID_SYNTAX = "FAMILY[:RESOLUTION][[OPTION=VALUE,...]]"
"""The form of every model id (``--model``, ``--reference``, ``request.models``)."""

_WIDTH = 100
"""Line width of the wrapped descriptions."""


def option_record(opt: Option) -> dict:
    """JSON form of an option: name, meaning, allowed values, default, bare value."""
    return {
        "name": opt.name,
        "doc": opt.doc,
        "values": list(opt.allowed),
        "default": opt.default,
        "bare": opt.bare,
    }


def family_record(fam: Family) -> dict:
    """JSON form of a family: id syntax, resolution, options and capabilities."""
    res = fam.resolution
    return {
        "name": fam.name,
        "summary": fam.summary,
        "syntax": fam.syntax,
        "resolution": None
        if res is None
        else {
            "name": res.name,
            "meaning": res.meaning,
            "default": res.default,
            "low": res.low,
            "high": res.high,
        },
        "options": [option_record(o) for o in fam.options],
        "capabilities": sorted(fam.capabilities),
        "plugin": plugin_of(fam.name),
    }


def catalogue_record() -> dict:
    """Every registered family (:func:`family_record`) and the meaning of each capability."""
    return {
        "id_syntax": ID_SYNTAX,
        "families": [family_record(f) for f in families()],
        "capabilities": {c: CAPABILITY_DOCS[c] for c in sorted(CAPABILITIES)},
    }


def _wrapped(label: str, text: str, indent: int) -> list[str]:
    return textwrap.wrap(
        text,
        _WIDTH,
        initial_indent=label.ljust(indent),
        subsequent_indent=" " * indent,
        break_on_hyphens=False,
    )


def format_models() -> str:
    """The ``flexval models`` listing: families, options, descriptions, capabilities."""
    fams = families()
    rows = []
    for f in fams:
        res = f.resolution
        rows.append(
            [
                f.name,
                f.syntax,
                "-" if res is None else res.name,
                "-" if res is None else str(res.default),
                "-" if res is None else f"{res.low}..{res.high}",
                ", ".join(o.name for o in f.options) or "-",
                ", ".join(sorted(f.capabilities)) or "-",
            ]
        )
    lines = [
        f"Model ids: {ID_SYNTAX}, e.g. beam:100[shear], dcmm:2[frame=follower]",
        "(quote ids with brackets in a shell; several options are separated by commas).",
        "",
    ]
    lines += text_table(
        [
            Column("family", "<"),
            Column("id syntax", "<"),
            Column("resolution", "<"),
            Column("default"),
            Column("range", "<"),
            Column("options", "<"),
            Column("capabilities", "<"),
        ],
        rows,
    )
    options = [
        [f.name, o.name, "|".join(o.allowed), o.default, o.bare or "-"]
        for f in fams
        for o in f.options
    ]
    if options:
        lines += ["", "Options (inside the brackets; a value left out is the default):", ""]
        lines += text_table(
            [
                Column("family", "<"),
                Column("option", "<"),
                Column("values", "<"),
                Column("default", "<"),
                Column("bare name means", "<"),
            ],
            options,
        )
    indent = max(len(f.name) for f in fams) + 2 if fams else 2
    lines += ["", "What each family is:", ""]
    for f in fams:
        res = f.resolution
        text = f.summary
        if res is not None:
            text += (
                f". {res.name}: {res.meaning}, {res.low} to {res.high} "
                f"(default {res.default}: '{f.name}' is '{f.name}:{res.default}')"
            )
        for o in f.options:
            text += f". Option {o.name}: {o.doc}"
        if plugin_of(f.name):
            text += f". From the plug-in package {plugin_of(f.name)}"
        lines += _wrapped(f.name, text + ".", indent)
    lines += ["", "Capabilities:", ""]
    width = max(len(c) for c in CAPABILITIES) + 2
    lines += [f"{c.ljust(width)}{CAPABILITY_DOCS[c]}" for c in sorted(CAPABILITIES)]
    return "\n".join(lines)
