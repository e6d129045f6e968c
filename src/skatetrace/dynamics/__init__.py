"""Dynamics: the Chaplygin sleigh steered by a moving mass, its parameters and its integrators.

The bottom layer. The equations of motion (:mod:`.model`), parameters for a real skater
(:mod:`.presets`), sampled control schedules (:mod:`.controls`), simulation under any controls
(:mod:`.simulate`) and the compiled Runge–Kutta core (:mod:`.dop853`, :mod:`.integrator`,
:mod:`.replayer`). Nothing here knows about figures, fitting or files.
"""
