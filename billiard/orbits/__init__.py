"""Periodic orbits: the impacts' return map (and the map through a contact phase on
the shaken table), its exact Jacobian, Newton's method for a
fixed point, its Floquet multipliers, and the continuation of a branch of orbits through
a scene key (docs/orbits.md)."""
