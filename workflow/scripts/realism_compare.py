"""results/realism/: the measured image against the model, effect by effect (thin)."""

import logging

from speckle.analysis.measured import roi_slices
from speckle.figures import realism
from speckle.io import load_image, to_netcdf
from speckle.pipeline.outputs import save
from speckle.pipeline.runner import run
from speckle.provenance import provenance_attrs
from speckle.studies.twin import fit_system

STEP_STATS = ("score", "ks_distance", "skewness", "excess_kurtosis")


def main(snakemake) -> None:
    cfg, seed = snakemake.params.realism, snakemake.params.seed
    meas_cfg = cfg["measured"]
    roi = air = fit = None
    reason = ""
    if not meas_cfg["path"]:
        reason = "not configured (realism.measured.path is null)"
    elif not hasattr(snakemake.input, "measured"):
        reason = f"not found at {meas_cfg['path']}"
    else:
        # pitch 1 µm: not recorded for this device, and only the waist/pitch ratio is fitted
        image = load_image(
            snakemake.input.measured,
            kind=meas_cfg["kind"],
            pixel_size=cfg["pixel_size"],
            pitch=1.0,
            dims=("depth", "x"),
        )
        roi_cfg = meas_cfg.get("roi") or {}
        roi = image.isel(roi_slices(roi_cfg, image.shape)).assign_attrs(roi=repr(roi_cfg))
        if meas_cfg.get("air_rows"):
            air = image.isel(roi_slices({"depth": meas_cfg["air_rows"]}, image.shape))
        # the effect parameters: one use of the twin's fit (speckle.studies.twin)
        fit = fit_system(
            image,
            region={"depth": roi_cfg.get("depth"), "x": roi_cfg.get("x")},
            noise_rows=meas_cfg.get("air_rows"),
            snr_db=None if meas_cfg.get("air_rows") else cfg["fallback"]["snr_db"],
            n_pixels=cfg["n_pixels"],
            max_lag=cfg["max_lag"],
            n_blocks=cfg["n_blocks"],
            n_bands=0,
        )
    if roi is None:
        logging.getLogger("realism").warning("measured image %s; drawing the model only", reason)
    ds = realism.realism_dataset(roi, air, cfg, seed, reason, fit=fit)
    ds.attrs.update(provenance_attrs(config={"realism": cfg}, seed=seed))
    to_netcdf(ds, snakemake.output.data)
    save(realism.plot_realism(ds), snakemake.output.figure)
    print(f"measured: {ds.attrs['measured']}")
    for k in [v for v in ds.data_vars if v.startswith("fit_")]:
        print(f"{k} = {float(ds[k]):.5g}")
    print(f"final (smallest sufficient) effects: {ds.attrs['final_effects']}")
    if "needed" in ds:
        for e in ds.effect.values:
            print(
                f"without {e}: score {float(ds.dropped_score.sel(effect=e)):.2f}, "
                f"KS {float(ds.dropped_ks_distance.sel(effect=e)):.4f}, "
                f"needed {bool(ds.needed.sel(effect=e))}"
            )
        for s in ds.step.values:
            c = {k: float(ds[f"cumulative_{k}"].sel(step=s)) for k in STEP_STATS}
            print(f"{s}: " + ", ".join(f"{k} {v:.4f}" for k, v in c.items()))
    print(f"wrote {snakemake.output.data} and {snakemake.output.figure}")


run(main)
