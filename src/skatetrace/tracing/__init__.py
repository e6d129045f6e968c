"""Tracing: the mass motion under which the sleigh follows every piece of a figure exactly.

The constrained dynamics on a curve and the launch, glide and stop manoeuvres (:mod:`.maneuver`),
where a section's glide may be placed (:mod:`.placements`), and the tracing of sections from rest to rest
into a figure's trace (:mod:`.sections`).
"""
