"""results/twin/: fit the system to a measured image, compare, predict failure maps (thin)."""

from speckle.figures import twin
from speckle.io import to_netcdf
from speckle.pipeline.outputs import save
from speckle.pipeline.runner import run
from speckle.provenance import provenance_attrs


def main(snakemake) -> None:
    cfg, seed = dict(snakemake.params.twin), snakemake.params.seed
    cfg["image"] = snakemake.input.image
    fit, compare, failure = twin.twin_datasets(cfg, seed)
    prov = provenance_attrs(config={"twin": snakemake.params.twin}, seed=seed)
    for ds, name in ((fit, "fit"), (compare, "compare"), (failure, "failure")):
        ds.attrs.update(prov)
        to_netcdf(ds, snakemake.output[name])
    save(twin.plot_compare(compare), snakemake.output.compare_figure)
    save(twin.plot_failure(failure), snakemake.output.failure_figure)
    for k in fit.data_vars:
        if not k.endswith("_se") and fit[k].ndim == 0:
            se = fit.get(f"{k}_se")
            print(f"{k} = {float(fit[k]):.5g}" + ("" if se is None else f" +- {float(se):.2g}"))
    print("spectrum shape:", fit.attrs["spectrum_shape"], "focused:", fit.attrs["focused"])
    for k in [v for v in compare.data_vars if v.startswith("z_")]:
        print(f"{k} = {float(compare[k]):.2f}")
    print(failure.rms_error.to_pandas())
    print(failure.answered.to_pandas())


run(main)
