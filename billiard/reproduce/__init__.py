"""The paper's reproduction: calibration, the four runs, the figures and docs/paper-
reproduction.md.
"""
