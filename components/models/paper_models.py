"""The paper's identified yaw models and table values as named data (Kayacan et al., section IV
and its Table): one home, read by the components' defaults, identification, analysis and tests.

Transfer functions are steer angle [rad] -> yaw rate [rad/s], coefficients highest power first.
"""
from __future__ import annotations

from typing import NamedTuple


class TransferFunction(NamedTuple):
    num: tuple[float, ...]
    den: tuple[float, ...]


# G_2nd, the empirical second-order model the MPC uses (section V), at 2 m/s
G_2ND = TransferFunction((291.0,), (1.0, 10.9, 242.0))
# the physical models identified at 2 m/s (section IV-B)
G_RLF = TransferFunction((292.0, 177.0), (1.0, 11.6, 249.0, 150.0))
G_RLFR = TransferFunction((279.0, 335.0, 27860.0), (1.0, 11.5, 347.0, 1311.0, 23340.0))

IDENTIFIED = {"second_order": G_2ND, "rlf": G_RLF, "rlfr": G_RLFR}

# time-domain validation RMSE [rad/s] on fresh 0-2 Hz and 0-8 Hz multisines (the paper's table)
VALIDATION_RMSE = {"second_order": {"0-2Hz": 0.0787, "0-8Hz": 0.0854}, "rlf": {"0-2Hz": 0.0787, "0-8Hz": 0.0854},
                   "rlfr": {"0-2Hz": 0.0793, "0-8Hz": 0.0860}}

# the physical parameters the paper estimates from G_RLFR (Table)
PHYSICAL = {"C_f": 8000.0, "C_r": 90000.0, "sigma_f": 0.1942, "sigma_r": 1.6657}

# Named physical parameter sets of the yaw plant (components.tractor_yaw_plant ``parameter_set``).
# "table": the paper's Table. With it the RLFR model has a weakly unstable mode (real part +0.015
# to +0.035 1/s near 10.3 rad/s at 1-2.5 m/s) that the identified G_RLFR (-0.62 +/- 9.95j) does
# not have. "rlfr_identified": C_f, C_r, sigma_f, sigma_r fitted to G_RLFR's denominator at 2 m/s
# with m, I, l_f, l_r from the Table (the section IV physical-parameter fit, on the poles): its
# poles are G_RLFR's at 2 m/s and it is stable at every speed; its numerator is
# 317 s^2 + 791 s + 32580 (G_RLFR: 279 s^2 + 335 s + 27860), a DC gain 17% higher.
RLFR_IDENTIFIED = {"C_f": 9847.149, "C_r": 41172.213, "sigma_f": 0.22223145, "sigma_r": 0.79988041}
PARAMETER_SETS = {"table": dict(PHYSICAL), "rlfr_identified": RLFR_IDENTIFIED}
DEFAULT_SET = {"rlfr": "rlfr_identified"}        # model -> set used when a study names none; else "table"
