"""Drawings: a user's curve (SVG, points, a function) turned into a traceable figure.

Reading drawings into parametric paths (:mod:`.curves`, :mod:`.svg`), fitting them by arcs and
lines within a certified distance (:mod:`.fitting`) or by exact curvature splines (:mod:`.exact`),
and resolving whatever the user names into a figure (:mod:`.sources`).
"""
