"""Analyses of runs: Lyapunov exponent, calibration, the camera's view, the paper's phase
point.
"""
