"""Sphinx configuration of the ngtmc documentation site (build: ``docs/build.sh``).

Stack: myst-parser renders the Markdown pages of ``docs/``, sphinx-gallery executes
``examples/*.py`` into the gallery (``docs/gallery/``, generated), autodoc documents the public
names. Nothing is fetched from the web, at build time or when a page is opened: no intersphinx,
no MathJax (the docstrings' formulas are plain text), and the theme (furo) ships its assets.

Two pages are filled in at build time from the package itself, so they cannot fall behind it:
``api.md`` (the names of ``ngtmc.__all__`` and ``ngtmc.sensitivities.__all__``) and
``studies.md`` (``ngtmc.list_studies()`` with each study's ``TITLE`` and ``SUMMARY``). Each holds a
marker line ``<!-- ngtmc: ... -->`` that :func:`_fill_generated` replaces when the page is read.
"""
from __future__ import annotations

import inspect
import os
import re
import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
sys.path.insert(0, str(ROOT))          # the ngtmc of this tree, installed or not
sys.path.insert(0, str(Path(__file__).resolve().parent))   # docs/benchmark_tables.py
os.environ.setdefault("OMP_NUM_THREADS", "1")

import ngtmc  # noqa: E402

project = "ngtmc"
author = "the ngtmc authors"
copyright = "2026, the ngtmc authors"
release = version = ngtmc.__version__

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.napoleon",
    "sphinx_gallery.gen_gallery",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "build.sh", "gallery/*.ipynb", "gallery/*.py", "gallery/*.zip",
                    "gallery/*.md5", "gallery/*.codeobj.json", "gallery/*.json"]

# Markdown: `[text](page.md#a-heading)` links between pages resolve to the page and the heading
# anchor (GitHub's slugs for headings of levels 1 to 4).
myst_heading_anchors = 4
myst_enable_extensions = ["colon_fence"]

# API reference
autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_default_options = {"members": True}
autosummary_generate = False           # api.md documents every name on the page itself
napoleon_google_docstring = False
napoleon_numpy_docstring = True
napoleon_use_ivar = True               # "Attributes" sections as fields, not as second entries

# The gallery: every examples/*.py is executed (in the full mode; NGTMC_EXAMPLE_SHORT=1 in the
# environment runs the short one); the examples print their numbers, they draw no figures.
sphinx_gallery_conf = {
    "examples_dirs": str(ROOT / "examples"),
    "gallery_dirs": "gallery",
    "filename_pattern": r"/\d\d_",
    "ignore_pattern": r"__init__\.py",
    "within_subsection_order": "FileNameSortKey",
    "image_scrapers": (),
    "reset_modules": (),               # no matplotlib to reset (the examples draw nothing)
    "download_all_examples": False,
    "remove_config_comments": True,
    "show_memory": False,
    "write_computation_times": False,  # its page loads DataTables from a CDN
    "abort_on_example_error": True,
    "reference_url": {},
    "plot_gallery": "True",
}

html_theme = "furo"
html_title = f"ngtmc {release}"
html_static_path = ["_static"]               # report.png, the picture of the README and of outputs.md
html_show_sourcelink = False
html_copy_source = False


# ----------------------------------------------------------------- pages filled in at build time
def _api_block(module_name: str, names: list[str]) -> str:
    """An autosummary table and one autodoc entry per public name of ``module_name``."""
    import importlib
    module = importlib.import_module(module_name)
    rows, entries = [], []
    for name in names:
        obj = getattr(module, name)
        full = f"{module_name}.{name}"
        if inspect.ismodule(obj):
            first = (inspect.getdoc(obj) or "").split("\n\n")[0].replace("\n", " ")
            entries.append(f".. rubric:: {full}\n\nThe module ``{obj.__name__}``: {_escape_bars(first)}\n")
        elif inspect.isclass(obj) and issubclass(obj, BaseException):
            rows.append(f"   {full}")
            entries.append(f".. autoexception:: {full}\n")
        elif inspect.isclass(obj):
            rows.append(f"   {full}")
            entries.append(f".. autoclass:: {full}\n")
        elif callable(obj):
            rows.append(f"   {full}")
            entries.append(f".. autofunction:: {full}\n")
        else:
            entries.append(f".. py:data:: {full}\n   :value: {obj!r}\n\n"
                           f"   {_data_doc(module_name, name)}\n")
    table = ".. autosummary::\n   :nosignatures:\n\n" + "\n".join(rows) + "\n"
    return "```{eval-rst}\n" + table + "\n" + "\n".join(entries) + "```\n"


def _escape_bars(text: str) -> str:
    """``|x|`` (an absolute value or norm in a plain-text docstring) would be read by
    reStructuredText as a substitution: escape each ``|`` outside inline literals."""
    parts = re.split(r"(``.*?``)", text)
    return "".join(p if p.startswith("``") else p.replace("|", r"\|") for p in parts)


def _hanging_fields(lines: list[str]) -> list[str]:
    """Docstrings written as plain-text field lists, ``name: text`` with hanging indented
    continuation lines (``ngtmc.Case``), are no reStructuredText (an indented line inside a
    paragraph is an error): such a paragraph becomes a bullet list, one item per field."""
    out, i = [], 0
    field = re.compile(r"^(\s*)([A-Za-z_][\w]*): (.*)$")
    while i < len(lines):
        j = i
        while j < len(lines) and lines[j].strip():
            j += 1
        block = lines[i:j]
        base = min((len(b) - len(b.lstrip()) for b in block), default=0)
        heads = [b for b in block if len(b) - len(b.lstrip()) == base]
        hanging = len(heads) < len(block)
        if block and hanging and all(field.match(b) for b in heads) and len(heads) > 1:
            items = []
            for b in block:
                m = field.match(b)
                if m and len(m.group(1)) == base:
                    items.append(f"{m.group(1)}- ``{m.group(2)}``: {m.group(3)}")
                else:
                    items[-1] += " " + b.strip()
            out += items
        else:
            out += block
        out += lines[j:j + 1]
        i = j + 1
    return out


def _plain_text_docstring(app, what, name, obj, options, lines):
    lines[:] = [_escape_bars(line) for line in _hanging_fields(lines)]


def _data_doc(module_name: str, name: str) -> str:
    return {"__version__": "The version of ngtmc.",
            "HISTORY_UNITS": "The unit of every column of a run's history "
                             "(``SimulationResult.history``; the force's unit is ``N/mm`` in 2D, "
                             "per the scene's thickness, ``N`` in 3D)."}.get(name, "")


def _studies_block() -> str:
    """One section per named study: its name on the command line, title, summary, resolutions."""
    out = []
    for name in ngtmc.list_studies():
        study = ngtmc.load_study(name)
        cli = name.replace("_", "-")
        resolutions = ", ".join(getattr(study, "RESOLUTIONS", {}))
        out.append(f"## `{cli}`\n\n**{study.TITLE}**\n\n{study.SUMMARY.strip()}\n\n"
                   f"Run: `ngtmc run {cli}` (resolutions: {resolutions}; default "
                   f"{getattr(study, 'DEFAULT_RESOLUTION', 'quick')}). Parameters: `ngtmc show {cli}`. "
                   f"Source: `studies/{name}.py` (`ngtmc.studies.{name}`).\n")
        expected = getattr(study, "EXPECTED", {}) or {}
        if expected:
            out.append("What its run is held to (`EXPECTED`; `tests/test_expected.py` checks the quick run):\n")
            out.append("| quantity | case | reference | tolerance | source |\n|:---|:---|---:|---:|:---|")
            for key, e in expected.items():
                unit = "" if e.get("unit") in (None, "-") else " " + e["unit"]
                tol = f"{100 * e['rel']:g} %" if e.get("rel") is not None else (
                    f"{e.get('abs'):g}{unit}" if e.get("abs") is not None else "-")
                value = e.get("value")
                value = f"{value:.5g}{unit}" if isinstance(value, (int, float)) else str(value)
                out.append(f"| {e.get('quantity', key)} | {e.get('case', '-')} | {value} | {tol} | "
                           f"{_escape_bars(str(e.get('source', '')))} |")
            out.append("")
        records = ROOT / "studies" / "records" / f"{name}.json"
        if records.is_file():
            out.append(f"Measured runs, each with its command, date and commit: `studies/records/{name}.json` "
                       f"(`ngtmc.study.records(\"{name}\")`)."
                       + (" Why the peaks differ from the published ones: [Fidelity](fidelity.md)."
                          if name == "three_point_bending" else "") + "\n")
    return "\n".join(out)


def _fill_generated(app, docname, source):
    text = source[0]
    if docname == "api":
        import ngtmc.sensitivities as sens
        text = text.replace("<!-- ngtmc: api ngtmc -->", _api_block("ngtmc", list(ngtmc.__all__)))
        text = text.replace("<!-- ngtmc: api ngtmc.sensitivities -->",
                            _api_block("ngtmc.sensitivities", list(sens.__all__)))
        import ngtmc.design as design
        text = text.replace("<!-- ngtmc: api ngtmc.design -->", _api_block("ngtmc.design", list(design.__all__)))
    elif docname == "studies":
        text = text.replace("<!-- ngtmc: studies -->", _studies_block())
    elif docname == "benchmarks":
        import benchmark_tables
        text = text.replace("<!-- ngtmc: benchmarks -->", benchmark_tables.block())
    source[0] = text


def _outside_links_as_downloads(app, doctree):
    """A Markdown link to a file of the repository outside ``docs/`` (the measured records of
    ``benchmarks/results/*.md``) is no page of the site: myst makes it a reference to a document
    that does not exist. Where that file exists it becomes a download link instead (the file is
    copied into the site, so the link works offline); a link to a file that does not exist keeps
    its warning."""
    from sphinx import addnodes
    src = Path(app.srcdir)
    for node in list(doctree.findall(addnodes.pending_xref)):
        if node.get("reftype") != "myst" or node.get("refdomain") != "doc":
            continue
        target = Path(node["reftarget"])
        if not target.is_absolute() or src in target.parents:
            continue
        files = [target.with_name(target.name + suffix) for suffix in (".md", ".rst")]
        existing = [f for f in files if f.is_file()]
        if not existing:
            continue
        here = (src / app.env.docname).parent
        link = addnodes.download_reference(refdoc=app.env.docname, refdomain=None, reftype="myst",
                                           refexplicit=True,
                                           reftarget=os.path.relpath(existing[0], here))
        link += node.children
        node.replace_self(link)


def setup(app):
    app.connect("source-read", _fill_generated)
    app.connect("autodoc-process-docstring", _plain_text_docstring, priority=600)   # after napoleon
    app.connect("doctree-read", _outside_links_as_downloads, priority=100)          # before the download collector
