# Phantoms fitted to measured images (results/phantom/real/): per image of
# phantom_real.fit, speckle.real_tissue_phantom's Dataset and its figure. The rule takes the
# section (minus the other images) as params and the package modules its script imports as
# inputs (see common.smk).
PHANTOM_REAL_TARGETS = [
    f"{RESULTS}/phantom/real/{name}.{ext}"
    for name in config["phantom_real"]["fit"]
    for ext in ("nc", "png")
]


rule phantom_real:
    input:
        image=lambda wc: config["phantom_real"]["images"][wc.name]["image"],
        code=package_code(
            "speckle.figures.phantom_real", "speckle.io", "speckle.provenance"
        ),
    output:
        data=f"{RESULTS}/phantom/real/{{name}}.nc",
        figure=report(
            f"{RESULTS}/phantom/real/{{name}}.png",
            caption="../report/phantom_real.rst",
            category="Phantom fit",
            labels={"figure": "real tissue", "image": "{name}"},
        ),
    log:
        f"{RESULTS}/logs/phantom_real_{{name}}.log",
    wildcard_constraints:
        name="[^/]+",
    conda:
        "../envs/speckle.yaml"
    threads: 1
    params:
        section=lambda wc: {
            **section_without("phantom_real", "images", "fit"),
            "image": config["phantom_real"]["images"][wc.name],
        },
        seed=config["seed"],
    script:
        "../scripts/phantom_real.py"
