"""What every study shares: discovery and the table of runs, the stage runner and its executors, the study's own
command line, loading runs, markdown, figures, reliving the best individuals, and the measure commands' writes (the
claims' verdict rules are ``imrl_jax.analysis.claims``). Imports ``imrl_jax`` only; the studies
(``experiments/*.py``) import it.
"""
