"""Fitting a G1 surface to a dense scan: the control mesh, the least-squares fit, the deviation."""
