"""JUnit XML of the gate checks, as CI systems display test results.

The common JUnit schema that GitHub Actions (test-reporting actions),
GitLab (``artifacts:reports:junit``) and Jenkins (``junit`` step) read:
``testsuites`` > ``testsuite`` (one per gated model) > ``testcase`` (one per
scene, load case and metric; ``name``, ``classname``, ``time`` in seconds) >
``failure`` (``message``, ``type`` and the figures as text) for a check that
does not hold, and ``system-out`` with what a check compared where its value
alone does not say (:attr:`flexval.validation.studies.gate.Check.detail`: the critical
loads of ``limit_load``, the worst mode and the flexure density of
``frequency``; that neither model has a critical load where that check passes
without a value). Written atomically (:func:`flexval.validation.outputs.write_text`).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

from ..outputs import write_text
from ..report.tables import sig
from .gate import Check


def _failure_text(check: Check, reference: str) -> tuple[str, str, str]:
    """(type, message, body) of a failed check."""
    where = f"{check.model} on {check.scene} {check.case} against {reference}"
    detail = f"\n{check.detail}" if check.detail and check.detail != check.reason else ""
    if check.value is None:
        message = f"{check.metric}: no value: {check.reason}"
        return "NoResult", message, f"{where}: {check.reason}{detail}"
    message = f"{check.metric} = {sig(check.value)} % > {sig(check.threshold)} %"
    body = (
        f"{where}: {check.metric} error {check.value!r} % exceeds the threshold "
        f"{check.threshold!r} %{detail}"
    )
    return "AccuracyGate", message, body


def junit_xml(checks: list[Check], reference: str, name: str = "flexval gate") -> bytes:
    """The JUnit XML document of ``checks`` (UTF-8 bytes), one test suite per model."""
    models = list(dict.fromkeys(c.model for c in checks))
    root = ET.Element("testsuites", name=name)
    total_time = 0.0
    for model in models:
        own = [c for c in checks if c.model == model]
        time = sum({(c.scene, c.case): c.seconds for c in own}.values())
        total_time += time
        suite = ET.SubElement(
            root,
            "testsuite",
            name=f"{name}: {model} against {reference}",
            tests=str(len(own)),
            failures=str(sum(not c.passed for c in own)),
            errors="0",
            skipped="0",
            time=f"{time:.6f}",
        )
        for c in own:
            case = ET.SubElement(
                suite,
                "testcase",
                name=f"{c.scene} {c.case} {c.metric}",
                classname=f"flexval.gate.{model}",
                time=f"{c.seconds:.6f}",
            )
            if not c.passed:
                kind, message, body = _failure_text(c, reference)
                ET.SubElement(case, "failure", message=message, type=kind).text = body
            if c.detail:
                ET.SubElement(case, "system-out").text = c.detail
    root.set("tests", str(len(checks)))
    root.set("failures", str(sum(not c.passed for c in checks)))
    root.set("errors", "0")
    root.set("time", f"{total_time:.6f}")
    ET.indent(root)
    return ET.tostring(root, encoding="utf-8", xml_declaration=True) + b"\n"


def write_junit(path: str | Path, checks: list[Check], reference: str) -> Path:
    """Write :func:`junit_xml` of ``checks`` to ``path`` atomically."""
    return write_text(path, junit_xml(checks, reference).decode("utf-8"))
