"""The commands a user types, each ``python -m imrl_jax.NAME`` (parse, plan, ``cli.execute``), with the options and
sweeps they are made of; the top layer, imported by nothing in the package.
"""
