"""Fig. 1: one scatterer at 0, 1, 1.25 pixels, its A-scan and spectral components (thin)."""

from speckle.figures import static
from speckle.io import to_netcdf
from speckle.pipeline.outputs import save
from speckle.pipeline.runner import run
from speckle.provenance import provenance_attrs


def main(snakemake) -> None:
    fig1, source = snakemake.params.fig1, snakemake.params.source
    ds = static.single_scatterer(
        fig1["positions"],
        fig1["k0_dk"],
        n_pixels=fig1["n_pixels"],
        pixel_size=source["pixel_size"],
        shape=source["shape"],
        fwhm_fraction=source.get("fwhm_fraction"),
    )
    ds.attrs.update(provenance_attrs(config={"fig1": fig1, "source": source}))
    to_netcdf(ds, snakemake.output.data)
    save(static.plot_single_scatterer(ds), snakemake.output.figure)
    print(f"wrote {snakemake.output.data} and {snakemake.output.figure}")


run(main)
