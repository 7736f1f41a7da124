"""Fig. 6b/6c strain sweeps (thin): the rule's name picks the panel of speckle.figures.deformation.

The ``dask`` config is read here rather than taken as a rule param: the numbers do not depend on
the scheduler or the worker count, so changing them must not rerun the sweep.
"""

from speckle.figures import deformation
from speckle.io import to_netcdf
from speckle.pipeline import adapters
from speckle.pipeline.outputs import save
from speckle.pipeline.runner import run


def main(snakemake) -> None:
    params, panel = snakemake.params, snakemake.rule  # "fig6b" or "fig6c"
    dask = adapters.dask_options(snakemake.config["dask"], snakemake.threads)
    ds = getattr(deformation, f"{panel}_data")(params.source, params.fig6, dask, params.seed)
    to_netcdf(ds, snakemake.output.data)
    save(getattr(deformation, f"plot_{panel}")(ds), snakemake.output.figure)
    print(f"wrote {snakemake.output.data} and {snakemake.output.figure}")


run(main)
