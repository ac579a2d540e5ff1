"""A driven gravitational billiard with a finite, spinning ball and frictional impacts.

Equations come from a Kane's-method derivation (``billiard.derivation``) and run as
generated code (``billiard.generated``). See README.md for the commands.
"""

__version__ = "0.1.0"
