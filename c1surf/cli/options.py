"""Click options shared by the commands that build a surface."""
from __future__ import annotations

import click

from ..core.surface import TANGENT_RULES


def surface_options(command):
    """Add --blend, --alpha, --beta, --tangent-rule to a command."""
    options = [
        click.option("--blend", type=click.FloatRange(0.0, 1.0), default=0.5, show_default=True,
                     help="Doo-Sabin blend ratio alpha_f of every cell (A1): smaller follows the mesh more closely."),
        click.option("--alpha", type=click.FloatRange(0.0, 1.0), default=1.0, show_default=True,
                     help="Shape parameter of the bicubic tangent coefficients P_32 at each cell centre (A3)."),
        click.option("--beta", type=float, default=0.0, show_default=True,
                     help="Centre point S = S_C + beta (S_P - S_C) of each bicubic cell (section 1.3.3); 0 keeps the cell centroid."),
        click.option("--tangent-rule", type=click.Choice(TANGENT_RULES), default="symmetric", show_default=True,
                     help="Tangent plane at cell centres: 'symmetric' (A3) or 'corners' (A3a, from the C_i only)."),
    ]
    for option in reversed(options):
        command = option(command)
    return command
