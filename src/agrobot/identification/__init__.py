"""Yaw-dynamics identification (paper section IV): multisine design, nonparametric FRF with noise
and nonlinear-distortion variances, weighted frequency-domain NLS fits, physical parameters."""
