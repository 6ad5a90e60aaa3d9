"""MkDocs hooks of the flexval site: the generated parts of the pages.

- Markers in the Markdown pages (an HTML comment ``<!-- flexval:NAME -->`` on a
  line of its own) are replaced by text generated from the code, so the
  references cannot drift from what the code accepts: the scene file fields
  (:func:`flexval.geometry.scene.field_reference`), the sweep file fields
  (:func:`flexval.validation.sweep.fields.field_reference`), the command line
  (:func:`flexval.validation.cli.reference.cli_reference`), the model catalogue,
  the built-in scene and sweep files, a scene file of the repository
  (``<!-- flexval:toml PATH -->``, or any text file: ``<!-- flexval:file PATH -->``), the
  gates file fields (:func:`flexval.validation.studies.gatefile.field_reference`) and a
  ``flexval`` command's output, run while
  the site is built (``<!-- flexval:command ARGS -->``). An unknown marker
  fails the build.
- The package as it installs is linked under ``build/docs-src`` for
  mkdocstrings (see :func:`_link_package`).
- The published reports (``reports/paper``, ``reports/flexures``, ``reports/mechanisms``,
  ``reports/dynamics``, ``reports/threed``, ``reports/sweep_example``: Markdown
  and figures) are added to the site under
  ``validation/`` as they are, so their relative links resolve.
- Every script in ``examples/`` is run with this Python in a scratch folder;
  the gallery page shows its description, its source, what it printed and any
  figure it wrote there. Every notebook in ``examples/`` is executed (nbclient,
  this Python's kernel) and shown with its outputs (nbconvert), the notebook file
  offered for download. A failing example fails the build.
- MathJax is served from the site itself (the copy the ``jupyter-server-mathjax``
  package ships), so the equations render offline.
"""

from __future__ import annotations

import ast
import os
import re
import shlex
import subprocess
import sys
import tempfile
import time
from importlib import resources
from pathlib import Path

from mkdocs.structure.files import File, Files

ROOT = Path(__file__).resolve().parent.parent
"""The repository."""
REPORTS = {
    "paper": "reports/paper",
    "flexures": "reports/flexures",
    "mechanisms": "reports/mechanisms",
    "dynamics": "reports/dynamics",
    "threed": "reports/threed",
    "sweep_example": "reports/sweep_example",
}
"""Folders of published reports, by their folder under ``validation/`` in the site."""
REPORT_SUFFIXES = (".md", ".png", ".svg")
FIGURE_SUFFIXES = (".png", ".svg", ".jpg")
EXAMPLE_TIMEOUT = 300.0
"""Seconds an example may run before the build fails."""

PACKAGE_PARTS = ("__init__.py", "geometry", "reducedmodels", "validation")
"""What the package ``flexval`` is made of: the repository root's ``__init__.py`` and folders."""
API_SOURCES = ROOT / "build" / "docs-src"
"""Holds ``flexval/``, links to :data:`PACKAGE_PARTS` only (see :func:`_link_package`)."""

_ROLE = re.compile(
    r":(?:py:)?(?:mod|func|class|meth|attr|data|exc|obj|const):<code>(~?)([\w.]+?)(\(\))?</code>"
)
"""A docstring's Sphinx cross-reference role as Markdown renders it: ``:meth:<code>x</code>``."""
_MARKER = re.compile(r"^<!-- flexval:([a-z-]+)(?: (.*?))? -->$", re.MULTILINE)
_examples: dict[str, dict] = {}
_notebooks_run: dict[str, dict] = {}


def _cell(text: str) -> str:
    """``text`` on one line, safe inside a Markdown table cell."""
    return " ".join(text.split()).replace("|", "\\|")


def _catalogue() -> str:
    """A table of the registered model families: id syntax, resolution, options, capabilities."""
    import flexval.validation  # noqa: F401  (registers the continuum)
    from flexval.reducedmodels.catalogue import families

    rows = [
        "| family | id | resolution (default, range) | options | capabilities | what it is |",
        "|---|---|---|---|---|---|",
    ]
    for fam in families():
        res = fam.resolution
        resolution = (
            "none"
            if res is None
            else f"{res.name}: {res.meaning} ({res.default}, {res.low}–{res.high})"
        )
        options = "<br>".join(_cell(f"`{o.name}`: {o.describe()}") for o in fam.options)
        caps = ", ".join(sorted(fam.capabilities)) or "–"
        rows.append(
            f"| `{fam.name}` | `{fam.syntax}` | {_cell(resolution)} | {options or 'none'} | "
            f"{caps} | {_cell(fam.summary)} |"
        )
    return "\n".join(rows) + "\n"


def _builtin_scene(name: str) -> str:
    text = resources.files("flexval.geometry").joinpath("scenes", f"{name}.toml").read_text()
    return f"```toml\n{text.rstrip()}\n```\n"


def _builtin_sweep(name: str) -> str:
    text = (ROOT / "validation" / "data" / "sweeps" / f"{name}.toml").read_text()
    return f"```toml\n{text.rstrip()}\n```\n"


def _command(args: str) -> str:
    """``flexval ARGS`` run now in a scratch folder, shown with what it printed (an argument
    ``@/PATH`` is the repository's file PATH, shown as ``PATH``)."""
    flexval = Path(sys.executable).with_name("flexval")
    argv = [str(ROOT / a[2:]) if a.startswith("@/") else a for a in shlex.split(args)]
    with tempfile.TemporaryDirectory(prefix="flexval-docs-command-") as folder:
        proc = subprocess.run(
            [str(flexval), *argv],
            cwd=folder,
            env={**os.environ, "MPLBACKEND": "Agg", "COLUMNS": "100"},
            capture_output=True,
            text=True,
            timeout=EXAMPLE_TIMEOUT,
        )
    if proc.returncode != 0:
        raise RuntimeError(f"flexval {args} failed (exit {proc.returncode}):\n{proc.stderr}")
    shown = args.replace("@/", "")
    return f"```text\n$ flexval {shown}\n{proc.stdout.rstrip()}\n```\n"


def _toml_file(path: str) -> str:
    """A TOML file of the repository (a relative path), as a code block."""
    text = (ROOT / path).read_text(encoding="utf-8")
    return f"`{path}`:\n\n```toml\n{text.rstrip()}\n```\n"


def _source_file(path: str) -> str:
    """A text file of the repository (a relative path), as a code block in its language."""
    language = {".py": "python", ".toml": "toml", ".yml": "yaml", ".yaml": "yaml"}
    text = (ROOT / path).read_text(encoding="utf-8")
    return f"`{path}`:\n\n```{language.get(Path(path).suffix, 'text')}\n{text.rstrip()}\n```\n"


def _generators() -> dict:
    from flexval.geometry.scene import field_reference as scene_reference
    from flexval.validation.cli.reference import cli_reference
    from flexval.validation.studies.gatefile import field_reference as gates_reference
    from flexval.validation.sweep.fields import field_reference as sweep_reference

    return {
        "scene-reference": scene_reference,
        "scene-example": lambda: _builtin_scene("open_chain"),
        "closed-chain-example": lambda: _builtin_scene("closed_chain"),
        "sweep-reference": sweep_reference,
        "sweep-example": lambda: _builtin_sweep("open_chain_arcs"),
        "cli-reference": cli_reference,
        "catalogue": _catalogue,
        "examples": _gallery,
        "notebooks": _notebooks,
        "command": _command,
        "toml": _toml_file,
        "file": _source_file,
        "gates-reference": gates_reference,
    }


# ---------------------------------------------------------------- examples


def _run_examples() -> dict[str, dict]:
    """Run every example at once (one process each) in its own scratch folder."""
    scripts = sorted((ROOT / "examples").glob("*.py"))
    env = {**os.environ, "MPLBACKEND": "Agg", "PYTHONDONTWRITEBYTECODE": "1"}
    runs = {}
    for script in scripts:
        folder = Path(tempfile.mkdtemp(prefix=f"flexval-docs-{script.stem}-"))
        proc = subprocess.Popen(
            [sys.executable, str(script)],
            cwd=folder,
            env=env,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
        )
        runs[script.stem] = {"script": script, "folder": folder, "proc": proc, "start": time.time()}
    for name, run in runs.items():
        try:
            out, _ = run["proc"].communicate(timeout=EXAMPLE_TIMEOUT)
        except subprocess.TimeoutExpired:
            run["proc"].kill()
            raise RuntimeError(f"example {name} ran longer than {EXAMPLE_TIMEOUT:g} s") from None
        if run["proc"].returncode != 0:
            raise RuntimeError(f"example {name} failed (exit {run['proc'].returncode}):\n{out}")
        run["output"] = out
        run["seconds"] = time.time() - run["start"]
        run["figures"] = sorted(
            p for p in run["folder"].rglob("*") if p.suffix.lower() in FIGURE_SUFFIXES
        )
    return runs


def _run_notebooks() -> dict[str, dict]:
    """Execute every notebook of ``examples/`` in a scratch folder and convert it to Markdown
    with its outputs; each entry holds the Markdown and the output files (name -> bytes),
    which it links under ``examples/<name>/``."""
    import nbformat
    from nbclient import NotebookClient
    from nbconvert import MarkdownExporter

    found = {}
    for notebook in sorted((ROOT / "examples").glob("*.ipynb")):
        folder = Path(tempfile.mkdtemp(prefix=f"flexval-docs-{notebook.stem}-"))
        node = nbformat.read(notebook, as_version=4)
        start = time.time()
        try:
            NotebookClient(
                node,
                timeout=EXAMPLE_TIMEOUT,
                kernel_name="python3",
                resources={"metadata": {"path": str(folder)}},
            ).execute()
        except Exception as exc:
            raise RuntimeError(f"notebook {notebook.name} failed: {exc}") from None
        body, resources = MarkdownExporter().from_notebook_node(
            node, resources={"output_files_dir": f"examples/{notebook.stem}"}
        )
        found[notebook.stem] = {
            "path": notebook,
            "folder": folder,
            "markdown": body,
            "files": resources.get("outputs", {}),
            "seconds": time.time() - start,
        }
    return found


def _notebooks() -> str:
    """The gallery's notebooks: each executed, with its outputs, and its file to download."""
    parts = []
    for name, run in _notebooks_run.items():
        parts.append(
            f"`examples/{name}.ipynb` ([download](examples/{name}.ipynb)), executed while this "
            f"page was built ({run['seconds']:.1f} s)."
        )
        parts.append(run["markdown"])
    return "\n\n".join(parts) + "\n"


def _docstring_markdown(text: str) -> str:
    """A numpy-style module docstring as Markdown: sections bold, roles and ``code`` plain."""
    lines = text.splitlines()
    out = []
    for i, line in enumerate(lines):
        if re.fullmatch(r"-{3,}", line.strip()):
            continue
        if i + 1 < len(lines) and re.fullmatch(r"-{3,}", lines[i + 1].strip()):
            out += ["", f"**{line.strip()}**", ""]
            continue
        out.append(line)
    md = "\n".join(out)
    md = re.sub(r":[a-z]+:`~?([^`]+)`", r"`\1`", md)
    md = md.replace("``", "`")
    md = re.sub(r"^\* ", "- ", md, flags=re.MULTILINE)
    return md.strip()


def _gallery() -> str:
    """The examples gallery: per script its description, source, printed output and figures."""
    parts = []
    for name, run in _examples.items():
        source = run["script"].read_text()
        doc = ast.get_docstring(ast.parse(source)) or ""
        title, _, body = doc.partition("\n")
        parts.append(f"## {title.strip().rstrip('.')} {{#{name}}}")
        parts.append(
            f"`examples/{name}.py`, run while this page was built ({run['seconds']:.1f} s)."
        )
        parts.append(_docstring_markdown(body))
        parts.append(f"### Output\n\n```text\n{run['output'].rstrip()}\n```")
        for fig in run["figures"]:
            rel = fig.relative_to(run["folder"]).as_posix()
            parts.append(f"![{rel}](examples/{name}/{rel})")
        parts.append(
            f'??? example "Source: examples/{name}.py"\n\n    ```python\n'
            + "\n".join(f"    {line}" if line else "" for line in source.rstrip().splitlines())
            + "\n    ```"
        )
    return "\n\n".join(parts) + "\n"


# ---------------------------------------------------------------- API sources


def _link_package() -> None:
    """Make ``build/docs-src/flexval`` the package as it installs, for mkdocstrings to read.

    The repository root is the package ``flexval``, mapped by setuptools'
    ``package-dir``. Griffe (mkdocstrings' reader) cannot follow that mapping
    and, given the root, would read every Python file under it (tests,
    benchmarks, the virtual environment) as submodules. The folder made here
    holds links to the package's own parts only; ``mkdocs.yml`` puts it first
    on griffe's search path.
    """
    package = API_SOURCES / "flexval"
    package.mkdir(parents=True, exist_ok=True)
    for part in PACKAGE_PARTS:
        link, target = package / part, ROOT / part
        if link.is_symlink() and link.resolve() == target.resolve():
            continue
        if link.is_symlink() or link.exists():
            link.unlink()
        link.symlink_to(target, target_is_directory=target.is_dir())


_link_package()  # at import: before mkdocstrings looks for any module


# ---------------------------------------------------------------- hooks


def on_files(files: Files, config) -> Files:
    """Add the published reports and the examples' figures to the site."""
    for folder, source in REPORTS.items():
        for path in sorted((ROOT / source).iterdir()):
            if path.suffix.lower() in REPORT_SUFFIXES:
                files.append(
                    File.generated(
                        config, f"validation/{folder}/{path.name}", abs_src_path=str(path)
                    )
                )
    _examples.clear()
    _examples.update(_run_examples())
    for name, run in _examples.items():
        for fig in run["figures"]:
            rel = fig.relative_to(run["folder"]).as_posix()
            files.append(File.generated(config, f"examples/{name}/{rel}", abs_src_path=str(fig)))
    _notebooks_run.clear()
    _notebooks_run.update(_run_notebooks())
    for name, run in _notebooks_run.items():
        files.append(
            File.generated(config, f"examples/{name}.ipynb", abs_src_path=str(run["path"]))
        )
        for rel, content in run["files"].items():
            files.append(File.generated(config, rel, content=content))
    return files


def on_post_build(config) -> None:
    """Copy MathJax into the site; remove the examples' scratch folders."""
    import shutil

    import jupyter_server_mathjax

    shutil.copytree(
        Path(jupyter_server_mathjax.__file__).parent / "static",
        Path(config["site_dir"]) / "javascripts" / "mathjax",
        ignore=shutil.ignore_patterns("localization", "*.eot", "*.otf", "*.svg"),
        dirs_exist_ok=True,
    )
    for run in [*_examples.values(), *_notebooks_run.values()]:
        shutil.rmtree(run["folder"], ignore_errors=True)


def on_page_content(html: str, page, config, files) -> str:
    """Turn the docstrings' Sphinx roles into cross-references (plain code where unresolved).

    ``:meth:`~pkg.Class.method``` becomes a link to the documented object
    when mkdocs-autorefs knows the identifier, shown as ``method`` (``~``) or
    in full, and inline code otherwise: the roles are left for Sphinx-style
    readers of the source, and mkdocstrings does not interpret them.
    """

    def link(match: re.Match) -> str:
        tilde, target, call = match.groups()
        shown = (target.rsplit(".", 1)[-1] if tilde else target) + (call or "")
        return f'<autoref identifier="{target}" optional><code>{shown}</code></autoref>'

    return _ROLE.sub(link, html)


def on_page_markdown(markdown: str, page, config, files) -> str:
    """Replace each ``<!-- flexval:NAME -->`` marker by its generated Markdown."""
    generators = _generators()

    def expand(match: re.Match) -> str:
        name, args = match.group(1), match.group(2)
        if name not in generators:
            raise KeyError(
                f"{page.file.src_uri}: unknown marker flexval:{name}; known: {sorted(generators)}"
            )
        return generators[name](args) if args else generators[name]()

    return _MARKER.sub(expand, markdown)
