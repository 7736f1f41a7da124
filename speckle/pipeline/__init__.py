"""The pipeline's package: everything between a config file and the package.

Config checks (every section, at workflow load), config adapters (a config section -> the
keyword arguments of a public function), the runner of workflow scripts and the figure style.
Workflow scripts import only public names from here and from the top level.
"""
