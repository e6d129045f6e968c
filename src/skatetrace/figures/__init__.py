"""Figures: what the blade must trace, as exact arcs, lines and spirals joined smoothly or at cusps.

Plane geometry of pieces (:mod:`.geometry`), the figure format with its joins and repeats
(:mod:`.figure`), and the built-in figures: the paper's patterns (:mod:`.patterns`) and the school
figures for a given skater (:mod:`.school`).
"""
