"""The pipeline's figures: data builders and plotting functions, one module per results folder.

Each figure module (:mod:`~speckle.figures.static`, :mod:`~speckle.figures.beam`,
:mod:`~speckle.figures.elastography`, ...) follows one convention:

* ``<name>_data(...) -> xarray.Dataset`` computes the numbers of figure ``<name>`` from a
  config section (plain keyword arguments, seeds included) and returns them as a labelled
  Dataset (units and long names from :mod:`speckle.conventions`);
  it writes nothing.
* ``plot_<name>(ds) -> matplotlib.figure.Figure`` draws that Dataset, read back from its
  NetCDF file if need be, and returns the Figure; it computes nothing the Dataset does not
  hold and writes nothing.
* The workflow script (``workflow/scripts/<rule>.py``, kept thin) saves both: the Dataset with
  :func:`speckle.io.to_netcdf` and the Figure with :func:`speckle.pipeline.outputs.save`, each
  atomically.

A few builders are named after what they build (``psf_dataset``, ``rolloff_dataset``,
``fig4_dataset``, ``twin_datasets``) and return the same kind of Dataset(s). The shared look
is :mod:`speckle.figures.style` (backend, rcParams, :func:`~speckle.figures.style.new_figure`);
config sections become keyword arguments in :mod:`speckle.pipeline.adapters` and are checked in
:mod:`speckle.pipeline.checks`, never here. This package has no lazy public names of its own:
import the modules, e.g. ``from speckle.figures import beam``.
"""
