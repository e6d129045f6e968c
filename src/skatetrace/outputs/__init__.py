"""Outputs: result files, plots, the animation and the HTML viewer of a traced figure.

Files written atomically and JSON written strictly (:mod:`.files`), output folders checked before
any work and holding one run's files (:mod:`.folder`), the result files of a trace
(:mod:`.results`), the paper's kinds of plots
(:mod:`.plotting`), a traced figure read back from its files (:mod:`.playback`), the animation
(:mod:`.animation`) and the self-contained viewer (:mod:`.viewer`, with its page in ``web/``).
"""
