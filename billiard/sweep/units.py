"""Units of the scene keys a sweep can vary (for axis labels and the result file)."""

from __future__ import annotations

__all__ = ["axis_label", "key_long_name", "key_unit", "variable_name"]

_UNITS = {
    "boundary.ceiling": "m",
    "boundary.escape_height": "m",
    "drive.amplitude": "m",
    "drive.frequency": "Hz",
    "drive.phase": "rad",
    "ball.radius": "m",
    "ball.mass": "kg",
    "ball.inertia_factor": "1",
    "contact.restitution": "1",
    "contact.mu_static": "1",
    "contact.mu_kinetic": "1",
    "contact.elastic_below": "m/s",
    "contact.beta0": "1",
    "contact.e_ref": "1",
    "contact.v_ref": "m/s",
    "contact.exponent": "1",
    "contact.viscous": "(s/m)^(1/5)",
    "contact.energy_scale": "J",
    "contact.angle_slope": "1",
    "air.c_lin": "N s/m",
    "air.c_quad": "N s^2/m^2",
    "air.magnus": "kg",
    "initial.q1": "m",
    "initial.q2": "m",
    "initial.v1": "m/s",
    "initial.v2": "m/s",
    "initial.omega": "rad/s",
    "initial.t": "s",
    "run.collisions": "1",
    "run.rtol": "1",
    "run.step": "s",
    "run.gravity": "m/s^2",
    "run.duration": "s",
    "run.contact_span": "s",
}

#: What each key is, in words (the result file's ``long_name``: xarray labels its plots'
#: axes "drive frequency [Hz]" from it and ``units``).
_NAMES = {
    "boundary.ceiling": "lid height",
    "boundary.escape_height": "escape height",
    "drive.amplitude": "drive amplitude",
    "drive.frequency": "drive frequency",
    "drive.phase": "drive phase",
    "ball.radius": "ball radius",
    "ball.mass": "ball mass",
    "ball.inertia_factor": "inertia factor I/(m r^2)",
    "contact.restitution": "coefficient of restitution",
    "contact.mu_static": "static friction coefficient",
    "contact.mu_kinetic": "kinetic friction coefficient",
    "contact.elastic_below": "elastic-impact speed threshold",
    "contact.law": "impact law",
    "contact.beta0": "tangential restitution of the contact point",
    "contact.e_ref": "restitution at the reference speed",
    "contact.v_ref": "reference impact speed",
    "contact.exponent": "restitution's speed exponent",
    "contact.viscous": "viscoelastic dissipation",
    "contact.energy_scale": "restitution's energy scale",
    "contact.angle_slope": "restitution's rise with the angle of incidence",
    "air.c_lin": "linear drag coefficient",
    "air.c_quad": "quadratic drag coefficient",
    "air.magnus": "Magnus coefficient",
    "initial.q1": "initial horizontal position",
    "initial.q2": "initial height",
    "initial.v1": "initial horizontal velocity",
    "initial.v2": "initial vertical velocity",
    "initial.omega": "initial spin",
    "initial.t": "initial time",
    "run.collisions": "impacts per run",
    "run.rtol": "relative tolerance",
    "run.step": "time step",
    "run.gravity": "gravitational acceleration",
    "run.duration": "simulated time",
    "run.contact_span": "contact span",
}


def key_long_name(key: str) -> str:
    """The key in words, as a plot's axis names it ("drive frequency"); a key without a
    description (a curve parameter, a text key) is named "scene key KEY"."""
    if key.startswith("boundary.parameters."):
        return f"curve parameter {key.rsplit('.', 1)[-1]}"
    return _NAMES.get(key, f"scene key {key}")


def key_unit(key: str) -> str:
    """The SI unit of a scene key ("1" for dimensionless; curve parameters take the
    units of their curve expression, in which x and f are metres)."""
    if key.startswith("boundary.parameters."):
        return "as in the curve expression (x, f in m)"
    return _UNITS.get(key, "1")


def axis_label(key: str) -> str:
    """``drive.frequency (Hz)``; dimensionless keys are labelled ``(1)``."""
    unit = key_unit(key)
    if key.startswith("boundary.parameters."):
        unit = "curve units"
    return f"{key} ({unit})"


def variable_name(key: str) -> str:
    """The result file's name for a swept key: dots become underscores."""
    return key.replace(".", "_").replace("-", "_")
