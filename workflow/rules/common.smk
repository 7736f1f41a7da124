# Helpers shared by all rule files.
import os

from speckle.pipeline.adapters import resolve_source
from speckle.provenance import config_hash, module_sources

RESULTS = config.get("results", "results")
# A source named by its datasheet gets its model parameters (n_pixels, pixel_size, k0_dk, ...).
config["source"] = resolve_source(config["source"])


def package_code(*modules):
    """Package source files used by a rule's script (so editing them reruns the rule).

    Snakemake tracks a rule's own script but not installed package code; list the package
    modules the script imports, e.g. package_code("speckle.figures.static"): their sources and
    every package module they import become inputs. Every script runs through the pipeline's
    runner and saves through its outputs module, so those two are always inputs.
    """
    every = ("speckle.pipeline.runner", "speckle.pipeline.outputs")
    return [os.path.relpath(p) for p in module_sources(*modules, *every)]


def section(*names):
    """The config sections a rule depends on, as params (a change reruns the rule)."""
    return {name: config[name] for name in names}


def section_without(name, *keys):
    """A config section minus the keys a rule does not read (changing them does not rerun it)."""
    return {k: v for k, v in config[name].items() if k not in keys}
