"""The engine's hot path as plain functions over floats and one state vector, compiled
by numba when it is available (:mod:`billiard.jit`) and interpreted otherwise.

One concept per module:

* :mod:`~billiard.kernels.layout`: where each quantity lives in the state vector ``ctx``
  (a float64 array; a list of Python floats when interpreted), the codes;
* :mod:`~billiard.kernels.names`: the state vector by name, for the wings outside the
  kernels and the engine;
* :mod:`~billiard.kernels.ball`: the generated ball equations, under the same decorator;
* :mod:`~billiard.kernels.flight`: the exact flight and the Dormand-Prince flight;
* :mod:`~billiard.kernels.surfaces`: gaps, rates and bounds of the offset walls, lid
  and escape level; the wall functions arrive as first-class function values;
* :mod:`~billiard.kernels.locate`: the event locator (bound, root refinement);
* :mod:`~billiard.kernels.fixed_step`: the paper's fixed-step detection (method ``rk4``);
* :mod:`~billiard.kernels.impact`: Kane and Levinson's law with the low-velocity rule;
* :mod:`~billiard.kernels.contact_equations`: the generated contact equations;
* :mod:`~billiard.kernels.contact_forces`: a contact phase's forces, rates and
  transition functions;
* :mod:`~billiard.kernels.contact`: a rolling or sliding phase on one wall, resumable
  at sample times;
* :mod:`~billiard.kernels.vertex`: a hold by two walls (the ball in a vertex), resumable
  at sample times;
* :mod:`~billiard.kernels.lid`: the ball pressed against the lid, in closed form;
* :mod:`~billiard.kernels.loop`: one impact, and ``run_chunk`` (up to N impacts into a
  preallocated array; ``run_chunk_fixed`` for method ``rk4``).

:mod:`~billiard.kernels.machine`: the trajectory state machine, the one engine that
  advances every scene; :mod:`~billiard.kernels.samples`: its trajectory samples.

:mod:`billiard.engine.driver` builds the state vector from a scene and runs the chunks.
:mod:`billiard.kernels.interpreted` loads these files again as plain Python
(``billiard.kernels_py``), which the runtime's classes call.
"""
