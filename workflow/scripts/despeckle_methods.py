"""results/despeckle/{phantom,methods}: every method on the phantom by every metric (thin)."""

from speckle.figures import despeckle
from speckle.io import to_netcdf
from speckle.pipeline.outputs import save
from speckle.pipeline.runner import run
from speckle.provenance import provenance_attrs


def main(snakemake) -> None:
    cfg, seed = snakemake.params.despeckle, snakemake.params.seed
    methods, phantom = despeckle.methods_data(cfg, seed)
    for ds in (methods, phantom):
        ds.attrs.update(provenance_attrs(config={"despeckle": cfg}, seed=seed))
    to_netcdf(phantom, snakemake.output.phantom)
    to_netcdf(methods, snakemake.output.data)
    save(despeckle.plot_phantom(phantom), snakemake.output.phantom_figure)
    save(despeckle.plot_methods(methods), snakemake.output.figure)
    print(f"wrote {', '.join(snakemake.output)}")


run(main)
