"""Every figure module follows one convention: ``*_data`` (or a named builder) computes a
Dataset, ``plot_<name>(ds, ...) -> Figure`` draws it, the workflow script saves both."""

from __future__ import annotations

import importlib
import inspect

import pytest
from matplotlib.figure import Figure

MODULES = [
    "beam",
    "deformation",
    "despeckle",
    "dynamics",
    "elastography",
    "histograms",
    "realism",
    "speed",
    "static",
    "system",
    "twin",
]


@pytest.mark.parametrize("name", MODULES)
def test_plot_functions_return_a_figure_and_write_nothing(name):
    mod = importlib.import_module(f"speckle.figures.{name}")
    public = {n: getattr(mod, n) for n in mod.__all__}
    assert not [n for n in public if n.endswith("_figure")], "use plot_<name>(ds) -> Figure"
    plots = {n: f for n, f in public.items() if n.startswith("plot_")}
    assert plots, f"{name} draws nothing"
    for n, f in plots.items():
        sig = inspect.signature(f)
        assert sig.return_annotation in (Figure, "Figure"), n
        assert not {"path", "path_png", "filename"} & set(sig.parameters), f"{n} must not save"
