"""Sphinx configuration of the springchain documentation: ``sphinx-build -W --keep-going docs docs/_build/html``.

Pages are MyST Markdown (``myst_nb``: pages with ``{code-cell}`` blocks are executed when the site
is built, so their outputs come from the code); the example gallery is ``sphinx_gallery``
(``docs/examples/*.py``, executed at build time); the scene, command and API references are
generated from the code (``_ext/springchain_sphinx.py``, and ``reference/api.rst`` written below from
``springchain.__all__``).
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE / "_ext"))
os.environ.setdefault("SPRINGCHAIN_PROGRESS", "0")  # no progress lines in executed outputs
os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import springchain  # noqa: E402

project = "springchain"
author = "the springchain authors"
copyright = "the springchain authors"
release = version = springchain.__version__

extensions = [
    "myst_nb",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "numpydoc",
    "sphinx_gallery.gen_gallery",
    "sphinx_copybutton",
    "springchain_sphinx",
]

exclude_patterns = ["_build", "_generated", "examples/*", "auto_examples/*.ipynb", "auto_examples/*.py",
                    "auto_examples/*.zip", "benchmarks/*", "**.ipynb_checkpoints", "jupyter_execute"]
templates_path = ["_templates"]
source_suffix = {".rst": "restructuredtext", ".md": "myst-nb", ".ipynb": "myst-nb"}
root_doc = "index"
smartquotes = False  # "--flag" stays two hyphens in prose

# -- MyST and executed pages -------------------------------------------------------------------------
myst_enable_extensions = ["dollarmath", "colon_fence", "deflist", "substitution"]

#: Limits the pages quote, read from the code (``{{ NAME }}`` in a page): each number is written once.
CODE_NUMBERS = {
    "MAX_DENSE": "springchain.generated.contract:MAX_DENSE",
    "MAX_MPMATH_MODES": "springchain.derive.accurate:MAX_MPMATH_MODES",
    "MAX_MODES_LISTED": "springchain.derive.chain:MAX_MODES_LISTED",
    "MODES_LISTED_EACH_END": "springchain.derive.chain:MODES_LISTED_EACH_END",
    "MAX_SYMBOLIC_BLOCK": "springchain.derive.modes:MAX_SYMBOLIC_BLOCK",
    "MAX_ROOT_OPS": "springchain.derive.modes:MAX_ROOT_OPS",
    "MAX_DET_TERMS": "springchain.derive.work:MAX_DET_TERMS",
    "MAX_ZETA_OPS": "springchain.derive.damping_report:MAX_ZETA_OPS",
    "TRANSFER_MAX_MASSES": "springchain.derive.transfer:MAX_MASSES",
    "DAMPED_CHAIN_MAX": "springchain.numeric.modes.chain_damping:DENSE_MAX",
    "DAMPED_CHAIN_MP_MAX": "springchain.numeric.modes.chain_damping:MP_MAX",
    "LOADED_CHAIN_EXACT_MAX": "springchain.numeric.system:LOADED_CHAIN_EXACT_MAX",
    "MODAL_MP_MAX_MASSES": "springchain.numeric.structural.modal_quantities:MP_MAX_MASSES",
    "FRF_MPMATH_MAX_MASSES": "springchain.numeric.frf.dense:MPMATH_MAX_MASSES",
    "PLAN_MAX_MASSES": "springchain.numeric.plan.planner:MAX_MASSES",
    "COMPILED_FORCE_MIN_N": "springchain.numeric.compiled.fast:COMPILED_FORCE_MIN_N",
    "SWEEP_IN_PROCESS_SECONDS": "springchain._sweep:IN_PROCESS_SECONDS",
    "NEWMARK_DENSE_MAX": "springchain.numeric.integrators.newmark:DENSE_MAX",
    "CELL_MAX_MASSES": "springchain.derive.bands.cell:MAX_CELL_MASSES",
    "CELL_MAX_REACH": "springchain.derive.bands.cell:MAX_REACH",
    "CELL_MAX_EXPANDED": "springchain.derive.bands.cell:MAX_EXPANDED",
    "BANDS_MAX_PERIOD": "springchain.derive.bands.model:MAX_PERIOD",
    "BANDS_MAX_POLY_CELL": "springchain.derive.bands.dispersion:MAX_POLY_CELL",
    "BANDS_POINTS": "springchain._bands:POINTS",
    "BANDS_MAX_Q": "springchain._bands:MAX_Q",
    "BANDS_OMEGA_POINTS": "springchain._bands:OMEGA_POINTS",
    "BANDS_FINITE_MAX": "springchain._bands:FINITE_MAX",
    "BANDS_GAP_RESOLUTION": "springchain.numeric.bands.edges:GAP_RESOLUTION",
    "BANDS_EDGE_CELLS": "springchain.numeric.bands.finite:EDGE_CELLS",
    "SPECTRUM_PERIOD_MIN": "springchain.numeric.structural.response_spectrum:PERIOD_RANGE[0]",
    "SPECTRUM_PERIOD_MAX": "springchain.numeric.structural.response_spectrum:PERIOD_RANGE[1]",
    "SPECTRUM_VALUE_LIMIT": "springchain.numeric.structural.response_spectrum:RECORD_VALUE_LIMIT",
    "SPECTRUM_MAX_WORK": "springchain.numeric.structural.response_spectrum:MAX_WORK",
    "SPECTRUM_SAMPLES_PER_PERIOD": "springchain.numeric.structural.sdof_peak:SAMPLES_PER_PERIOD",
    "SPECTRUM_LONG_CYCLES": "springchain.numeric.structural.sdof_peak:LONG_CYCLES",
    "SENS_MAX_ALL_MODES": "springchain._sensitivity:MAX_ALL_MODES",
    "SENS_MODES_EACH_END": "springchain._sensitivity:MODES_EACH_END",
    "SENS_MAX_SHAPE_MASSES": "springchain._sensitivity:MAX_SHAPE_MASSES",
    "VEERING_MAC": "springchain.numeric.sensitivity.tracking:VEERING_MAC",
    "IDENTIFIABLE_RTOL": "springchain.numeric.updating.fit:IDENTIFIABLE_RTOL",
    "RECONSTRUCT_MAX_MASSES": "springchain.numeric.updating.reconstruct:MAX_MASSES",
    "RECONSTRUCT_MAX_DIGITS": "springchain.numeric.updating.reconstruct:MAX_DIGITS",
    "STATE_SPACE_MAX_MASSES": "springchain._interop:MAX_DENSE_STATES",
    "STATE_SPACE_CONTRAST_NOTE": "springchain.numeric.interop.state_space:CONTRAST_NOTE",
    "FRF_FORMS_MAX_BASE_MASSES": "springchain._frf_forms:MAX_BASE_MASSES",
    "RANDOM_MAX_MASSES": "springchain.numeric.random.modal_form:MAX_MASSES",
    "RANDOM_MAX_POINTS": "springchain.numeric.random.psd_input:MAX_POINTS",
}


def _code_numbers() -> dict[str, str]:
    import importlib

    import re

    out = {}
    for name, where in CODE_NUMBERS.items():
        module, attr = where.split(":")
        attr, _, index = attr.partition("[")  # "NAME[0]": an item of a tuple
        value = getattr(importlib.import_module(module), attr)
        if index:
            value = value[int(index.rstrip("]"))]
        if isinstance(value, float):  # 4e9, 1e-150: no "e+09"
            out[name] = re.sub(r"e\+?(-?)0*(\d)", r"e\1\2", f"{value:g}")
        else:
            out[name] = f"{value:,}".replace(",", " ")
    return out


myst_substitutions = _code_numbers()
myst_heading_anchors = 3
nb_execution_mode = os.environ.get("SPRINGCHAIN_DOCS_EXECUTE", "cache")
nb_execution_cache_path = str(HERE / "_build" / ".jupyter_cache")
nb_execution_timeout = 600
nb_execution_raise_on_error = True
nb_execution_show_tb = True
nb_execution_in_temp = True
nb_merge_streams = True

# -- API reference: autosummary of the public namespace ----------------------------------------------
autosummary_generate = True
autodoc_typehints = "none"
autodoc_member_order = "bysource"
numpydoc_show_class_members = False
numpydoc_validation_checks: set[str] = set()


def _write_api_page() -> None:
    """``reference/api.rst``: every name of ``springchain.__all__``, functions then classes."""
    import inspect

    names = [n for n in springchain.__all__ if n != "__version__"]
    objs = {n: getattr(springchain, n) for n in names}
    functions = [n for n in names if inspect.isfunction(objs[n])]
    classes = [n for n in names if inspect.isclass(objs[n]) and not issubclass(objs[n], Exception)]
    errors = [n for n in names if inspect.isclass(objs[n]) and issubclass(objs[n], Exception)]
    other = [n for n in names if n not in functions + classes + errors]
    text = ["..", "   Written by docs/conf.py from springchain.__all__ on every build: do not edit.", "",
            "API reference", "=============", "",
            "Everything below is importable from the top of the package (``import springchain as sc``;",
            "``sc.load``, ``sc.modes``, ...). Each name is loaded on first use, so ``import springchain``",
            "stays cheap. The list is ``springchain.__all__``: a name added there appears here.", "",
            ".. currentmodule:: springchain", ""]
    for title, group in (("Functions", functions), ("Result and scene classes", classes),
                         ("Errors", errors), ("Other", other)):
        if not group:
            continue
        text += [title, "-" * len(title), "", ".. autosummary::", "   :toctree: generated", ""]
        text += [f"   {n}" for n in group] + [""]
    out = HERE / "reference" / "api.rst"
    new = "\n".join(text)
    if not out.exists() or out.read_text(encoding="utf-8") != new:
        out.write_text(new, encoding="utf-8")


_write_api_page()

# -- example gallery ---------------------------------------------------------------------------------


def springchain_scraper(block, block_vars, gallery_conf):
    """Figures made without pyplot (springchain never touches pyplot): every matplotlib Figure, every
    written GIF (``Animation.path``) and every PNG/GIF path that a block left in the example's
    globals (alone or in a list), shown once each, in the order the globals were bound."""
    import shutil

    from matplotlib.figure import Figure
    from sphinx_gallery.scrapers import figure_rst

    shown = gallery_conf.setdefault("_springchain_shown", {}).setdefault(block_vars["src_file"], set())
    paths = []
    it = block_vars["image_path_iterator"]
    for value in list(block_vars["example_globals"].values()):
        for v in (value if isinstance(value, (list, tuple)) else [value]):
            key = str(v) if isinstance(v, Path) else id(v)
            if key in shown:
                continue
            if isinstance(v, Figure):
                path = next(it)
                v.savefig(path, dpi=80)
            elif type(v).__name__ == "Animation" and getattr(v, "path", None):
                path = str(Path(next(it)).with_suffix(".gif"))
                shutil.copyfile(v.path, path)
            elif isinstance(v, Path) and v.suffix in (".png", ".gif") and v.is_file():
                path = str(Path(next(it)).with_suffix(v.suffix))
                shutil.copyfile(v, path)
            else:
                continue
            shown.add(key)
            paths.append(path)
    return figure_rst(paths, gallery_conf["src_dir"])


sphinx_gallery_conf = {
    "examples_dirs": "examples",
    "gallery_dirs": "auto_examples",
    "filename_pattern": r".*\.py$",
    "image_scrapers": (springchain_scraper,),
    "download_all_examples": False,
    "remove_config_comments": True,
    "within_subsection_order": "FileNameSortKey",
    "show_memory": False,
    "capture_repr": (),
    "abort_on_example_error": False,
    # each API page shows the gallery examples that use it (reference/generated/*.examples)
    "backreferences_dir": "reference/generated",
    "doc_module": ("springchain",),
    "inspect_global_variables": True,
    "only_warn_on_example_error": False,
}

# -- HTML ----------------------------------------------------------------------------------------------
html_theme = "pydata_sphinx_theme"
html_title = f"springchain {release}"
html_static_path: list[str] = []
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
    "secondary_sidebar_items": ["page-toc"],
    "footer_start": ["copyright"],
    "footer_end": [],
}
html_show_sourcelink = False
suppress_warnings = ["mystnb.unknown_mime_type", "config.cache"]


# -- docstrings ------------------------------------------------------------------------------------
def _absolute_bars(app, what, name, obj, options, lines):
    """``|H|`` in a docstring is an absolute value, not a reStructuredText substitution."""
    import re

    for i, line in enumerate(lines):
        lines[i] = re.sub(r"(?<![\\|`])\|(?=[^\s|])([^|\n`]{1,40}?)(?<=[^\s|])\|(?![|`])", r"\\|\1\\|", line)


def setup(app):
    app.connect("autodoc-process-docstring", _absolute_bars, priority=400)
