"""Outputs: result files, plots, the animation and the HTML viewer of a traced figure.

Result files written atomically into a managed folder (:mod:`.io`), the paper's kinds of plots
(:mod:`.plotting`), a traced figure read back from its files (:mod:`.playback`), the animation
(:mod:`.animation`) and the self-contained viewer (:mod:`.viewer`, with its page in ``web/``).
"""
