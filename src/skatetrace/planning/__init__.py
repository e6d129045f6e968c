"""Planning: the mass motion a skater could make (bounded reach, continuous on the ice, least effort), kept exact.

:func:`~skatetrace.planning.planner.plan_figure` poses each curve as a
multi-phase optimal-control program (:mod:`~skatetrace.planning.collocation`, CasADi and IPOPT),
refines its mesh against the compiled integrator (:mod:`~skatetrace.planning.mesh`) and finishes
every section exactly by multiple shooting (:mod:`~skatetrace.planning.finish`). Programs that do not
depend on each other are solved side by side in worker processes (:mod:`~skatetrace.planning.pool`).
"""
