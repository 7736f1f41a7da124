"""Studies: experiments that run imaging and analysis to study a method or a system.

A study builds scenes, images them (``speckle.imaging``) and measures the images
(``speckle.analysis``) to answer a question about a method: where a strain estimator fails, how
a speckle-suppression method trades resolution for contrast, how a twin of a measured scanner
is fitted, how motion decorrelates speckle. Studies stand above the estimators they study; the
estimators never import them.

``twin`` fits the model's system to a user's image and predicts its strain limits;
``realism`` scores which effect makes a simulated image look measured; ``failure`` scores strain
estimators on pairs of known strain (the failure maps); ``speed`` times the synthesis methods
against their accuracy and maps where each fails; ``suppression`` builds the
speckle-suppression phantom and scores images against its truth; ``looks`` forms the physical
compounding looks (angle, offset, polarization, time) of one scene; ``phantom`` fits a
layered SynthOCT phantom to a scan (the challenge's inverse problem), runs its closed loop over
virtual patients on Dask and scores it as the challenge scores.
Names load on first use (SPEC 1, ``lazy_loader``).
"""

from .._lazy import attach, functions_of

__getattr__, __dir__, __all__ = attach(
    __name__,
    {
        "dynamics": ["FLOW_CONTRASTS", *functions_of(__name__, "dynamics")],
        "dynamics_series": functions_of(__name__, "dynamics_series"),
        "looks": functions_of(__name__, "looks"),
        "phantom": [
            "PhantomFit",
            "fit_phantom",
            "phantom_closed_loop_case",
            "phantom_failure_map",
            "virtual_patient",
            "phantom_closed_loop",
        ],
        "twin": ["SystemFit", "fit_system"],
    },
)
