"""A3's hole rules: the n bicubic patches over an n-sided cell (``bicubic``, its sums over large rings
``cyclic_sums``), triangles' rule (``triangles``, section 1.3.4), a dart's hole (``dart``) and the table that picks
one per hole (``hole_rules``)."""
