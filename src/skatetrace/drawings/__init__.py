"""Drawings: a user's curve (SVG, points, a function) turned into a traceable figure.

Reading drawings into parametric paths (:mod:`.curves`, :mod:`.inputs`); cutting a path into smooth
runs at corners and cusps (:mod:`.splitting`) and spiral spans at inflections (:mod:`.spirals`);
fitting the runs by arcs and lines within a certified distance (:mod:`.fitting`: biarcs from
:mod:`.biarcs`, bounds from :mod:`.certify` and :mod:`.arc_distances`, results in
:mod:`.fit_results`, figures by :mod:`.to_figure`, corners by :mod:`.corners`) or by exact curvature
splines (:mod:`.exact`); and resolving whatever the user names into a figure (:mod:`.sources`).
"""
