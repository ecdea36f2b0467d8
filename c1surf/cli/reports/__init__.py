"""Commands that report on an input without converting it (``c1surf inspect``)."""
