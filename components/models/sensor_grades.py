"""The sensor grades the field studies assume, in one place (the IMU and odometry components and
the INS estimator take their defaults from here, so the filter's model and the simulated sensor
start equal; a study may set either apart to test a mismatch).

IMU: an industrial MEMS unit of the class sold for machine control and agricultural guidance.
Gyro: 0.008 deg/s/sqrt(Hz) rate noise density and 8 deg/h in-run bias stability (Analog Devices
ADIS16470 datasheet); the in-run bias is a first-order Gauss-Markov process with that standard
deviation and a 300 s correlation time (the usual approximation of the flicker floor, Groves,
*Principles of GNSS, Inertial, and Multisensor Integrated Navigation Systems*, 2nd ed., 4.4.3),
on top of a turn-on bias of 0.1 deg/s that the estimator learns while driving. Accelerometer:
100 ug/sqrt(Hz) noise, a 2 mg turn-on bias (factory-calibrated MEMS; the in-run instability,
13-30 ug, is left out). Roll and pitch come from the unit's own attitude filter (a VRU/AHRS):
Xsens quote 0.2 deg static, 0.3-0.5 deg dynamic (1 sigma) for their MTi VRU/AHRS; after the
installation's roll calibration (driving a line both ways, as every autosteer install does) we
take 0.1 deg as the residual offset per run and 0.05 deg white noise on a straight swath.

Wheel odometry: rear-wheel speed with the wheel slip of field work (typically 5-15 %; our
assumption, no datasheet): a scale error of 5 % (1 sigma) per run, wandering 1 % with a 30 s
correlation time as the soil changes, and 0.02 m/s white noise at 100 Hz.
"""
from __future__ import annotations

import math

DEG = math.pi / 180.0

GYRO_NOISE_DENSITY = 0.008 * DEG          # rad/s/sqrt(Hz)
GYRO_BIAS_INSTABILITY = 8.0 * DEG / 3600  # rad/s (1 sigma of the Gauss-Markov bias)
GYRO_BIAS_TIME_CONSTANT = 300.0           # s
GYRO_TURN_ON_BIAS = 0.1 * DEG             # rad/s (1 sigma)
ACCEL_NOISE_DENSITY = 100e-6 * 9.81       # m/s2/sqrt(Hz)
ACCEL_TURN_ON_BIAS = 2e-3 * 9.81          # m/s2 (1 sigma)
ATTITUDE_BIAS = 0.1 * DEG                 # rad (1 sigma, per run: the roll calibration's residual)
ATTITUDE_NOISE = 0.05 * DEG               # rad (1 sigma, white, per sample)

ODOMETRY_SCALE_ERROR = 0.05               # 1 sigma, per run
ODOMETRY_SLIP_WANDER = 0.01               # 1 sigma of the Gauss-Markov part
ODOMETRY_SLIP_TIME_CONSTANT = 30.0        # s
ODOMETRY_NOISE = 0.02                     # m/s per sample


# GNSS fix error, 1 sigma per axis, by GGA quality: RTK fixed is the paper's 2 cm; u-blox's ZED-F9P
# datasheet gives SBAS 1.0 m CEP (DGPS: 0.85 m per axis) and PVT 1.5 m CEP (single: 1.3 m per axis);
# RTK float, quoted by no datasheet, is taken as 0.3 m (decimetres, between the two)
FIX_ERROR_STD = {4: 0.02, 5: 0.3, 2: 0.85, 1: 1.3}
DEGRADED_ERROR_TIME_CONSTANT = 60.0       # s: the degraded fixes' error wanders (Gauss-Markov)


def gauss_markov_step(value, phi: float, std: float, draw):
    """x_{k+1} = phi x_k + sqrt(1 - phi^2) sigma w_k: a first-order Gauss-Markov process of stationary
    std sigma (phi = exp(-dt / T)); ``draw`` gives the standard normal w_k."""
    return phi * value + math.sqrt(max(1.0 - phi * phi, 0.0)) * std * draw
