"""Fig. 4: simulated intensity/amplitude histograms vs a measured B-scan (thin)."""

import logging

from speckle.analysis.measured import roi_slices
from speckle.figures import histograms
from speckle.io import load_image, to_netcdf
from speckle.pipeline import adapters
from speckle.pipeline.outputs import save
from speckle.pipeline.runner import run
from speckle.provenance import provenance_attrs


def main(snakemake) -> None:
    fig4, source, seed = snakemake.params.fig4, snakemake.params.source, snakemake.params.seed
    sim = histograms.simulated_panels(
        density=fig4["density"],
        n_alines=fig4["n_alines"],
        k0_dk=source["k0_dk"],
        seed=seed,
        **adapters.source_options(source),
        method=fig4["method"],
        floor=fig4["floor"],
        bins=fig4["bins"],
        intensity_max=fig4["intensity_max"],
        amplitude_max=fig4["amplitude_max"],
    )
    cfg = fig4["measured"]
    image, reason = None, ""
    if not cfg["path"]:
        reason = "not configured (fig4.measured.path is null)"
    elif not hasattr(snakemake.input, "measured"):
        reason = f"not found at {cfg['path']}"
    else:
        image = load_image(
            snakemake.input.measured,
            kind=cfg["kind"],
            dims=("depth", "x"),
            pixel_size=cfg["pixel_size"],
            pitch=cfg["pitch"],
        )
        roi = cfg.get("roi") or {}
        image = image.isel(roi_slices(roi, image.shape)).assign_attrs(roi=repr(roi))
    if image is None:
        logging.getLogger("fig4").warning(
            "measured image %s; drawing simulated panels only", reason
        )
    ds = histograms.fig4_dataset(sim, image, reason)
    ds.attrs.update(provenance_attrs(config={"fig4": fig4, "source": source}, seed=seed))
    to_netcdf(ds, snakemake.output.data)
    save(histograms.plot_fig4(ds), snakemake.output.figure)
    print(f"measured: {ds.attrs['measured']}")
    for k in (
        "sim_contrast",
        "sim_contrast_theory",
        "sim_exponential_mean",
        "sim_rayleigh_sigma",
        "measured_skewness",
        "measured_excess_kurtosis",
        "measured_floor",
        "measured_excess_kurtosis_model",
        "measured_ks_pure",
        "measured_ks_floor",
    ):
        if k in ds:
            print(f"{k} = {float(ds[k]):.4f}")
    print(f"wrote {snakemake.output.data} and {snakemake.output.figure}")


run(main)
