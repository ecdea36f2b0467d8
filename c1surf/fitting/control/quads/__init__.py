"""A control mesh by quad-mesh simplification: the scan turned into quads, coarsened and regularized locally.

``quad_mesh`` the representation, ``links`` and ``edits`` the compiled topology and the one transaction every
operation is, ``operations`` the local operations, ``validity`` an independent check, ``start`` the scan
turned into quads, ``rounds`` the compiled passes, ``smoothing`` the tangential smoothing projected onto the scan,
``sizing`` the edge length wanted, ``simplify`` the driver (docs/layout.md).
"""
