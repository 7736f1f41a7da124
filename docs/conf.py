"""Sphinx configuration of the speckle docs.

Build: ``sphinx-build -W -b html docs docs/_build/html`` (every warning is an error).

The API reference is written here, at every build, from the packages' ``__all__``: one page per
topic (scene, system, imaging, analysis, figures, I/O), each an autosummary table of the topic's
public names, so a new public name appears without editing the docs. ``check_api_coverage``
(after MetPy's ``override_check``) fails the build when a name of ``speckle.__all__`` or of a
subpackage's ``__all__`` is on no API page.
"""

from __future__ import annotations

import importlib
import os
import pkgutil
import shutil
from pathlib import Path

import speckle

os.environ.setdefault("MPLBACKEND", "Agg")

HERE = Path(__file__).parent
project = "speckle"
author = "the speckle developers"
copyright = "2026, the speckle developers"
release = version = speckle.__version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
    "numpydoc",
    "myst_parser",
    "sphinx_gallery.gen_gallery",
]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
exclude_patterns = ["_build", "**.ipynb_checkpoints", "auto_examples/*.md5"]
myst_enable_extensions = ["dollarmath", "colon_fence", "deflist"]
myst_heading_anchors = 3
suppress_warnings = ["myst.header"]

html_theme = "pydata_sphinx_theme"
html_title = "speckle"
html_static_path = ["_static"]
html_theme_options = {
    "show_toc_level": 2,
    "navigation_with_keys": False,
    "secondary_sidebar_items": ["page-toc"],
}
html_sidebars = {"**": ["sidebar-nav-bs"]}

autosummary_generate = True
autosummary_imported_members = True
autodoc_default_options = {"members": False}
autodoc_typehints = "none"  # numpydoc's Parameters section carries the types
numpydoc_show_class_members = False
numpydoc_xref_param_type = False
#: numpydoc validation, on every object the API reference documents (each failure is a
#: warning, so an error under -W): a docstring for every public object (GL08), documented
#: parameters that exist (PR02), parameter types and descriptions (PR05-PR10), return
#: descriptions (RT02, RT03), summary line form (SS01, SS03, SS04), layout (GL03, GL05-GL07,
#: GL09, GL10).
numpydoc_validation_checks = {
    "GL03", "GL05", "GL06", "GL07", "GL08", "GL09", "GL10",
    "PR02", "PR05", "PR06", "PR07", "PR09", "PR10",
    "RT02", "RT03",
    "SS01", "SS03", "SS04",
}  # fmt: skip
#: Not validated: constants (``ASCAN_METHODS``, ``ENGINE``, ...: data, documented by a ``#:``
#: comment where they are defined) and members of classes (``System``, ``Beam``: dataclass
#: fields are documented in the class's Attributes section; the class itself is validated).
numpydoc_validation_exclude = {r"\.[A-Z][A-Z0-9_]+$", r"\.[A-Z]\w*\.\w+$"}

sphinx_gallery_conf = {
    "examples_dirs": ["../examples"],
    "gallery_dirs": ["auto_examples"],
    "filename_pattern": r"/plot_",
    "within_subsection_order": "FileNameSortKey",
    "download_all_examples": False,
    "remove_config_comments": True,
    "abort_on_example_error": True,
    "matplotlib_animations": False,
    "image_scrapers": ("matplotlib",),
    # no rcParams reset between examples: the figure modules apply their shared style
    # (speckle.figures.style.STYLE: fonts, tight bounding box) once, on import
    "reset_modules": (),
    "show_memory": False,
    "write_computation_times": True,
}


# ---------------------------------------------------------------- the API reference
#: Topic pages: title, intro, and the sections (module -> names) each lists.
def _public(module: str) -> list[str]:
    return list(importlib.import_module(module).__all__)


def _modules_of(package: str) -> list[str]:
    """The public modules of ``package`` that define names (``__all__`` of their own), not
    the shims that keep an old path working (their names warn and live elsewhere)."""
    pkg = importlib.import_module(package)
    names = (
        f"{package}.{m.name}"
        for m in pkgutil.iter_modules(pkg.__path__)
        if not m.name.startswith("_")
    )
    return sorted(n for n in names if "__all__" in vars(importlib.import_module(n)))


def _figure_modules() -> list[str]:
    return _modules_of("speckle.figures")


def api_topics() -> dict[str, tuple[str, str, dict[str, list[str]]]]:
    """Topic -> (title, intro, {module: public names}) of the API reference pages."""
    groups = {
        "scene": ("Scene", "What is imaged: scatterers, shared scenes, regions, deformation, FEM."),
        "system": ("System", "The OCT system: source, datasheet, spectrometer chain, effects."),
        "imaging": ("Imaging", "Eq. 4 and its fast methods, B-scans, the scanned beam, scans."),
        "analysis": ("Analysis", "Statistics, correlation, tracking, strain, measured images."),
        "studies": (
            "Studies",
            "Experiments on methods and systems: the scanner's twin, realism, failure maps, "
            "speckle suppression, speckle in time, the SynthOCT inverse problem.",
        ),
        "synthoct": (
            "SynthOCT",
            "The open drop-in for the SynthOCT 2026 challenge's virtual scanner: its files, "
            "its scanner (and the ``speckle-scan`` command), its maps and metrics.",
        ),
    }
    topics = {
        name: (title, intro, {f"speckle.{name}": _public(f"speckle.{name}")})
        for name, (title, intro) in groups.items()
    }
    topics["figures"] = (
        "Figures",
        "One module per figure family: ``<name>_data(...) -> Dataset`` builds a figure's "
        "dataset from a config section, ``plot_<name>(ds) -> Figure`` draws it.",
        {m: _public(m) for m in _figure_modules()},
    )
    topics["pipeline"] = (
        "Pipeline",
        "Between a config file and the package: the load-time checks of every config section, "
        "the config adapters, the scripts' runner and the saving of figures.",
        {m: _public(m) for m in _modules_of("speckle.pipeline")},
    )
    topics["io"] = (
        "I/O and infrastructure",
        "Atomic NetCDF I/O, Dask sweeps, the names/units table and provenance.",
        {m: _public(m) for m in ("speckle.io", "speckle.sweep", "speckle.conventions",
                                 "speckle.provenance")},
    )  # fmt: skip
    return topics


def write_api_pages(app=None) -> None:
    """Write docs/api/<topic>.rst from the packages' ``__all__`` (autosummary tables)."""
    out = HERE / "api"
    out.mkdir(exist_ok=True)
    # autosummary's pages are regenerated at every build: a stub of a renamed or removed name
    # would otherwise stay and fail the build (it is imported, and -W makes that an error)
    shutil.rmtree(out / "generated", ignore_errors=True)
    for stale in out.glob("*.rst"):
        stale.unlink()
    for order, (topic, (title, intro, sections)) in enumerate(api_topics().items()):
        lines = [f".. _api-{topic}:", "", title, "=" * len(title), "", intro, ""]
        for module, names in sections.items():
            if topic == "figures" or topic == "io":
                lines += [f"``{module}``", "-" * (len(module) + 4), ""]
                doc = (importlib.import_module(module).__doc__ or "").strip().split("\n\n")[0]
                lines += [doc, ""] if doc else []
            lines += [f".. currentmodule:: {module}", "", ".. autosummary::",
                      "   :toctree: generated", ""]  # fmt: skip
            lines += [f"   {name}" for name in sorted(names, key=str.lower)] + [""]
        text = "\n".join(lines)
        (out / f"{order}_{topic}.rst").write_text(text)


def documented_names() -> set[str]:
    """Every ``module.name`` listed in an autosummary table of the API pages."""
    names = set()
    for path in (HERE / "api").glob("*.rst"):
        module = None
        for line in path.read_text().splitlines():
            if line.startswith(".. currentmodule::"):
                module = line.split("::")[1].strip()
            elif line.startswith("   ") and module and not line.strip().startswith(":"):
                names.add(f"{module}.{line.strip()}")
    return names


def required_names() -> set[str]:
    """Public names that must be in the API reference: the top level and every group."""
    import speckle

    required = set()
    groups = ("scene", "system", "imaging", "analysis", "studies", "synthoct")
    owners = {g: set(_public(f"speckle.{g}")) for g in groups}
    owners["io"] = set(_public("speckle.io"))
    for name in speckle.__all__:
        if name == "__version__":
            continue
        where = [g for g, names in owners.items() if name in names]
        required.add(f"speckle.{where[0]}.{name}" if where else f"speckle.{name}")
    pipeline = _modules_of("speckle.pipeline")
    for module in (*(f"speckle.{g}" for g in owners), *_figure_modules(), *pipeline):
        required |= {f"{module}.{n}" for n in _public(module)}
    return required


def check_api_coverage(app, env) -> None:
    """Fail the build when a public name is on no API page (MetPy's override_check)."""
    missing = sorted(required_names() - documented_names())
    if missing:
        from sphinx.errors import ExtensionError

        raise ExtensionError(f"public names missing from the API reference: {missing}")


def _keep_ranges_in_summaries() -> None:
    """Autosummary ends a summary at the first ``". "``, also inside ````q = 0 ... N-1````
    (then a broken literal, a docutils warning); an ellipsis character keeps such a range in
    one sentence of the summary table (the object's own page is unchanged)."""
    from sphinx.ext import autosummary

    extract = autosummary.extract_summary

    def extract_summary(doc: list[str], document) -> str:
        return extract([line.replace(" ... ", " \u2026 ") for line in doc], document)

    autosummary.extract_summary = extract_summary


def setup(app) -> None:
    write_api_pages()
    _keep_ranges_in_summaries()
    app.connect("env-check-consistency", check_api_coverage)
