"""What every study shares: discovery and the table of runs, the stage runner and its executors, the study's own
command line, loading runs, markdown, figures, reliving the best individuals, the claims' verdict rules, and the
measure commands' writes. Imports ``imrl_jax`` only; the studies (``experiments/*.py``) import it.
"""
