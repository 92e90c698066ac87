"""Runs on disk: run directories and their atomic writes, content keys, checkpoints, events and progress, an
evolution's and a learning test's state, and what the command lines share (check, then write).

Imports every layer but ``commands``.
"""
