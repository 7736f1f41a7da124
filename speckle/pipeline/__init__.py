"""The pipeline's package: everything between a config file and the package.

``checks`` refuses a config the schema lets through (every section, in one place, when the
workflow loads); ``adapters`` turns config sections into the keyword arguments and objects of
public functions; ``runner`` runs a workflow script with all its output in the rule's log;
``outputs`` writes a job's figure. Workflow scripts import only public names from here, from
the top level and from the figure modules. Names load on first use (SPEC 1, ``lazy_loader``);
they stay out of the top level (``speckle.run`` would say nothing there).
"""

from .._lazy import attach

__getattr__, __dir__, __all__ = attach(__name__, __file__)
