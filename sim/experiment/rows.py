"""The rows: Table 1's four, every other error of the paper's Sec. 3 alone, and all at once; their injectors.

A row is a name (``ROWS``; its position seeds the row's trials), a label for the tables and
figures, the injectors it attaches and, for Table 1's rows, the paper's simulated figures.
``RAISED_ROWS`` place the trial's cube on top of another (arrangements in layers).
"""

from __future__ import annotations

#: Rows: Table 1's four in the paper's order, then every other error of the paper's Sec. 3 alone,
#: then all of them at once. The position seeds a row's trials: append new rows, never reorder.
ROWS = (
    "system",
    "translation",
    "orientation",
    "grasp-estimator",
    "perception",
    "surface",
    "slip",
    "sticking",
    "release",
    "tilt",
    "all",
    "raised",
    "raised-translation",
)

#: Rows whose target stands on another part: a support cube ("green") at the trial's target, turned,
#: and the trial's cube ("red") on it; the figures are the raised cube's (``trial.raised_plan``).
RAISED_ROWS = ("raised", "raised-translation")


#: The default rows: the paper's Table 1.
TABLE1_ROWS = ROWS[:4]


#: The rows ``bt-arrange experiment`` runs without ``--rows``.
DEFAULT_ROWS = TABLE1_ROWS


ROW_LABELS = {
    "system": "1) System accuracy",
    "translation": "2) Translation error",
    "orientation": "3) Orientation error",
    "grasp-estimator": "4) Depth-only grasp estimator (substitute for Berscheid et al.)",
    "perception": "Perception error (Fig. 2a)",
    "surface": "Surface error (Fig. 2d)",
    "slip": "Grip error, slip (Fig. 2e)",
    "sticking": "Friction error, sticking (Fig. 2f)",
    "release": "Release error, height (Fig. 2g)",
    "tilt": "Tilting error (Fig. 2h)",
    "all": "All errors at once (Fig. 2a-h)",
    "raised": "Raised target: system accuracy (on another cube)",
    "raised-translation": "Raised target: translation error (on another cube)",
}


#: The injectors (``bt_arrange_sim.injection`` specs, default magnitudes) each row attaches, in order:
#: a later picking error is drawn to fit with an earlier one.
ROW_INJECTORS: dict[str, tuple[str, ...]] = {
    "system": (),
    "translation": ("pick_translation",),
    "orientation": ("pick_rotation",),
    "grasp-estimator": (),
    "perception": ("perception_offset",),
    "surface": ("surface_shift",),
    "slip": ("transport_slip",),
    "sticking": ("release_stick",),
    "release": ("release_height",),
    "tilt": ("release_tilt",),
    "all": (
        "perception_offset",
        "pick_translation",
        "pick_rotation",
        "surface_shift",
        "transport_slip",
        "release_stick",
        "release_height",
        "release_tilt",
    ),
    # On the raised cube only: the support is placed without injected errors.
    "raised": (),
    "raised-translation": ("pick_translation",),
}


#: Table 1 a), simulation: mean and std in mm after placing and after pushing (rows the paper ran).
#: The paper's Table 1, its real robot's column: after placing and after pushing, mean and std (mm).
PAPER_REAL_MM = {
    "system": (3.72, 2.30, 0.72, 0.34),
    "translation": (14.30, 7.95, 1.08, 0.56),
    "orientation": (4.18, 3.74, 0.80, 0.39),
    "grasp-estimator": (14.18, 10.72, 1.07, 0.50),
}

PAPER_SIMULATION_MM = {
    "system": (0.47, 0.29, 0.40, 0.25),
    "translation": (8.54, 5.70, 0.45, 0.41),
    "orientation": (3.03, 4.70, 0.43, 0.25),
    "grasp-estimator": (5.18, 3.83, 0.41, 0.25),
}


def row_injectors(row: str) -> list:
    """The errors a row injects (``ROW_INJECTORS``), each at its default magnitude, fresh for one run."""
    specs = ROW_INJECTORS[row]
    if not specs:
        return []
    from bt_arrange_sim.injection import make_injectors

    return make_injectors(specs)
