"""The pieces of bench/run.py: inputs and mesh files, processes, workers, fidelity, tolerance, report.

Nothing here imports c1surf at module level: c1surf is measured through its
command line (``python -m c1surf.cli.main convert ...``) in processes of their
own, and only the in-memory workers (``workers``) import it, inside the worker.
"""
