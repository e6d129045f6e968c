"""Drawings: a user's curve (SVG, points, a function) turned into a traceable figure.

Reading drawings into parametric paths (:mod:`.curves`): SVG (:mod:`.svg`), point lists
(:mod:`.points`), Python functions (:mod:`.functions`), any file by its suffix (:mod:`.load`), with
lengths, units and size limits in :mod:`.lengths` and file reading in :mod:`.files`. Cutting a path
into smooth runs at corners and cusps (:mod:`.splitting`) and spiral spans at inflections
(:mod:`.spirals`). Fitting the runs by arcs and lines within a certified distance (:mod:`.fitting`:
biarcs from :mod:`.biarcs`, bounds from :mod:`.certify` and :mod:`.arc_distances`, results in
:mod:`.fit_results`, figures by :mod:`.to_figure`, corners by :mod:`.corners`) or by exact curvature
splines (:mod:`.exact`: one span in :mod:`.exact_spans`, one run in :mod:`.exact_runs`, results in
:mod:`.exact_results`, the figure in :mod:`.exact_figure`). Resolving whatever the user names into a
figure (:mod:`.sources`).
"""
