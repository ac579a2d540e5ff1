"""Running a scene to its end: :func:`simulate`, its :class:`Result`, streamed runs and
resuming them.
"""
