"""Verification: independent checks of a trace, by replay through the full equations.

The replay and its deviation and conservation checks (:mod:`.verify`), the paper's deviation cost
(:mod:`.deviation`), and the plausibility verdict: could a person make these controls
(:mod:`.feasibility`)?
"""
