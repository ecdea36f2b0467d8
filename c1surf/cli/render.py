"""``c1surf render``: EXR images with exact per-pixel curvature, PNG previews, zebra stripes."""
from __future__ import annotations

import os
import warnings
from dataclasses import dataclass

import click
import numpy as np

from .. import __version__
from ..api import load_patches
from ..evaluation.curvature import CURVATURE_NAMES
from ..evaluation.patch_set import PatchSet
from ..io.atomic import atomic_output
from ..io.images.exr import write_exr
from ..io.images.png import write_png
from ..render.camera import PROJECTIONS, VIEWS, CameraPlacement, frame_camera
from ..render.image import GEOMETRY_NAMES, atlas_layout, default_tile, render, render_atlas
from ..render.pictures import COLORMAPS, curvature_picture, srgb_to_linear, zebra_picture
from ..render.raycast import default_resolution, patch_grid_mesh
from ..resources import check_memory
from .common import Failure, Progress, echo_notes, friendly_errors, output_suffix, with_formats
from .options import FiniteFloat, grouped, input_options, surface_options

# EXR channels, in the order listed by `c1surf render --help` (the file sorts them by name).
EXR_CHANNELS = ("R", "G", "B", "A") + CURVATURE_NAMES + GEOMETRY_NAMES
BYTES_PER_PIXEL = 450  # float64 buffers, rays, pictures and the EXR copy per pixel, measured (atlas: 1.4 GB / 3.2M)


def check_image_size(pixels: int) -> None:
    """Refuse an image that would not fit in memory, with the estimate."""
    check_memory(pixels * BYTES_PER_PIXEL, f"an image of {pixels} pixels", "lower --size (or --tile with --atlas)", None)


def parse_size(text: str) -> tuple[int, int]:
    """'1024x768' -> (1024, 768); '512' -> (512, 512)."""
    try:
        parts = [int(p) for p in str(text).lower().replace("*", "x").split("x")]
    except ValueError:
        parts = []
    if len(parts) == 1:
        parts = parts * 2
    if len(parts) != 2 or min(parts) < 1 or max(parts) > 32768:
        raise click.BadParameter(f"expected WIDTHxHEIGHT such as 1024x768 (1 to 32768 pixels), got {text!r}")
    return parts[0], parts[1]


def read_patches(input_path, surface, inputs, quiet: bool, progress: Progress) -> PatchSet:
    """The patches (with their weights and adjacency) of a mesh or patch file (``api.load_patches``), renderable."""
    patches, notes = load_patches(input_path, surface, inputs, progress.phase)
    echo_notes(notes, quiet)
    if patches.n_patches == 0:
        raise Failure(f"{input_path}: there are no patches to render")
    if any(max(g.shape[1:3]) > 4 for g in patches.groups):
        raise Failure(f"{input_path}: patches of degree above 3 are not supported")
    largest = max(float(np.abs(g[..., :3]).max()) for g in patches.groups if g.size)
    if largest > RENDER_MAX_COORDINATE:  # the camera and the EXR's attributes are float32 (3.4e38 at most)
        raise Failure(f"{input_path}: coordinates reach {largest:.3g}, beyond {RENDER_MAX_COORDINATE:.0e} where "
                      "rendering in single precision overflows: scale the model down to render it")
    return patches


RENDER_MAX_COORDINATE = 1e30  # the surface's coordinates render takes (its camera stands a few sizes away, in float32)


@dataclass(frozen=True)
class Images:
    """The files ``render`` writes: an EXR (``exr``), a PNG preview (``png``), reflection lines (``zebra``); None: not."""

    exr: str | None = None
    png: str | None = None
    zebra: str | None = None


@dataclass(frozen=True)
class Colours:
    """How ``render`` colours its pictures: the curvature shown (``quantity``), the colour map, its range (LO, HI)
    or None, and the zebra stripes (pairs per turn, the light lines' axis or None)."""

    quantity: str = "kmax"
    colormap: str = "viridis"
    value_range: tuple | None = None
    stripes: int = 16
    stripe_axis: tuple | None = None


def exr_channels(image, rgb: np.ndarray) -> dict:
    """The EXR channels of a rendered image: colour preview (linear light) and data."""
    linear = srgb_to_linear(rgb)
    data = {"R": linear[..., 0], "G": linear[..., 1], "B": linear[..., 2], "A": image.mask.astype(np.float32),
            **image.channels}
    return {name: data[name] for name in EXR_CHANNELS}


def check_outputs(images: Images, value_range) -> None:
    """Usage errors in the output options: nothing to write, wrong suffixes, one file twice, an empty range."""
    output, png_path, zebra_path = images.exr, images.png, images.zebra
    if not (output or png_path or zebra_path):
        raise click.UsageError("nothing to write: give -o IMAGE.exr, --png PREVIEW.png and/or --zebra ZEBRA.png")
    if output:
        output_suffix(output, {".exr": None}, "--output")
    for path, what in ((png_path, "--png"), (zebra_path, "--zebra")):
        if path:
            output_suffix(path, {".png": None}, what)
    outputs = [p for p in (output, png_path, zebra_path) if p]
    if len({os.path.abspath(p) for p in outputs}) != len(outputs):
        raise click.BadParameter("-o, --png and --zebra must name different files")
    if value_range is not None and not value_range[1] > value_range[0]:
        raise click.BadParameter(f"--range needs LO < HI, got {value_range[0]} {value_range[1]}")


def place_camera(points: np.ndarray, width: int, height: int, camera: CameraPlacement):
    """``frame_camera`` with the command's camera options; bad ones become one-line failures."""
    try:
        return frame_camera(points, width, height, placement=camera)
    except ValueError as e:  # eye on the target, surface behind the eye
        raise Failure(str(e)) from None


def atlas_image(patches: PatchSet, tile, width: int, height: int, camera: CameraPlacement, progress: Progress):
    """The atlas of the patches, with a camera placed from the control points for its depth."""
    tile = tile or default_tile(patches.n_patches)
    rows, columns = atlas_layout(patches.n_patches, tile)
    check_image_size(rows * columns * tile * tile)
    progress.phase(f"atlas of {patches.n_patches} patches")
    # Control points bound the surface (convex hull), enough to place the camera.
    control = np.concatenate([g[..., :3].reshape(-1, 3) for g in patches.groups])
    return render_atlas(patches, tile, place_camera(control, width, height, camera), progress=progress.advance)


def view_image(patches: PatchSet, mesh_resolution, width: int, height: int, camera: CameraPlacement,
               progress: Progress):
    """The surface seen through a camera that frames the ray-casting mesh."""
    n = mesh_resolution or default_resolution(patches.n_patches)
    progress.phase(f"tessellating {patches.n_patches} patches at {n} x {n} for ray casting")
    mesh = patch_grid_mesh(patches.groups, n, patches.weights)
    return render(patches, place_camera(mesh.points, width, height, camera), progress=progress.advance, mesh=mesh)


def image_notes(image) -> None:
    """Notes on how the image was made: the slow ray caster, an empty picture."""
    if image.info.get("engine") == "trimesh":
        click.echo("c1surf: note: embreex is not installed (pip install embreex); ray casting used trimesh's "
                   "fallback, about 1 ms per pixel", err=True)
    if not image.mask.any():
        click.echo("c1surf: note: the surface is not in the picture (check --eye, --target, --zoom)", err=True)


def exr_attributes(image, quantity: str, colour_range) -> dict:
    """EXR header attributes: version, kind, colouring, patch count, camera (and the atlas layout)."""
    atlas = "tile" in image.info
    attributes = {"c1surfVersion": __version__, "c1surfKind": "atlas" if atlas else "render",
                  "c1surfColorBy": quantity, "c1surfColorRange": list(colour_range),
                  "c1surfPatches": int(image.info["patches"])}
    attributes.update(image.camera.attributes())
    if atlas:
        attributes.update({"c1surfTile": int(image.info["tile"]), "c1surfColumns": int(image.info["columns"])})
    return attributes


def write_atomically(path, input_path, progress: Progress, write) -> None:
    """If ``path``: ``write(tmp)`` a temporary file that becomes ``path`` once complete."""
    if path:
        progress.phase(f"writing {path}")
        with atomic_output(path, inputs=[input_path]) as tmp:
            write(tmp)


def image_options(command):
    """-o, --png, --zebra: the command receives them as one ``images`` argument (``Images``)."""
    return grouped(command, "images", [
        click.option("-o", "--output", type=click.Path(dir_okay=False), default=None,
                     help="EXR image of float32 channels: R G B A (preview, linear), kmax K H k1 k2 (curvature), Z "
                          "(depth along the view), N.X N.Y N.Z (unit normal), P.X P.Y P.Z (position), patch (-1 = "
                          "background), u v."),
        click.option("--png", "png_path", type=click.Path(dir_okay=False), default=None,
                     help="Also write a shaded preview coloured by curvature, with a colour bar."),
        click.option("--zebra", "zebra_path", type=click.Path(dir_okay=False), default=None,
                     help="Also write reflection lines (zebra stripes): continuous on a G1 surface, broken where "
                          "normals jump."),
    ], lambda output, png_path, zebra_path: Images(output, png_path, zebra_path))


def camera_options(command):
    """--view, --eye, --target, --up, --projection, --fov, --zoom: one ``camera`` argument (``CameraPlacement``)."""
    return grouped(command, "camera", [
        click.option("--view", type=click.Choice(sorted(VIEWS)), default="iso", show_default=True,
                     help="Camera direction for a Y-up scene (front looks along -Z, top along -Y, side along -X)."),
        click.option("--eye", type=FiniteFloat(), nargs=3, default=None, metavar="X Y Z",
                     help="Camera position (overrides --view)."),
        click.option("--target", type=FiniteFloat(), nargs=3, default=None, metavar="X Y Z",
                     help="Point looked at [default: centre of the bounding box]."),
        click.option("--up", type=FiniteFloat(), nargs=3, default=None, metavar="X Y Z",
                     help="Up direction [default: +Y, or the view's]."),
        click.option("--projection", type=click.Choice(PROJECTIONS), default="perspective", show_default=True,
                     help="Pinhole camera, or parallel rays (orthographic: only the direction of --eye/--view counts)."),
        click.option("--fov", type=FiniteFloat(0.1, 170.0), default=None,
                     help="Vertical field of view in degrees (perspective) [default: 30, or framing everything with "
                          "--eye]."),
        click.option("--zoom", type=FiniteFloat(1e-6, 1e6), default=1.0, show_default=True,
                     help="Magnify about the image centre (the whole surface is framed at 1)."),
    ], lambda **values: CameraPlacement(**values))


def colour_options(command):
    """--color-by, --colormap, --range, --stripes, --stripe-axis: one ``colours`` argument (``Colours``)."""
    return grouped(command, "colours", [
        click.option("--color-by", "quantity", type=click.Choice(CURVATURE_NAMES), default="kmax", show_default=True,
                     help="Curvature shown by the colours (R G B and --png)."),
        click.option("--colormap", type=click.Choice(sorted(COLORMAPS)), default="viridis", show_default=True,
                     help="'viridis' (perceptual) or 'gray' (the paper's black-to-white ramp)."),
        click.option("--range", "value_range", type=FiniteFloat(), nargs=2, default=None, metavar="LO HI",
                     help="Colour range [default: 0 to the 98th percentile of |value| on screen; symmetric when "
                          "signed]."),
        click.option("--stripes", type=click.IntRange(1, 10000), default=16, show_default=True,
                     help="--zebra: black and white stripe pairs per turn of the reflected ray."),
        click.option("--stripe-axis", type=FiniteFloat(), nargs=3, default=None, metavar="X Y Z",
                     help="--zebra: direction of the parallel light lines [default: the camera's up]. Normals that "
                          "jump across an edge show best with lines along that edge."),
    ], lambda **values: Colours(**values))


@click.command("render")
@click.argument("input_path", metavar="INPUT|PATCHES", type=click.Path(dir_okay=False))
@image_options
@camera_options
@click.option("--size", default="1024x1024", show_default=True, metavar="WxH", help="Image size WIDTHxHEIGHT (or N for N x N).")
@click.option("--atlas", is_flag=True,
              help="Parameter space instead of a view: patch k is a square tile (u to the right, v up), same channels.")
@click.option("--tile", type=click.IntRange(1, 4096), default=None,
              help="--atlas: pixels per patch side [default: as large as fits about 4 million pixels, at most 32].")
@colour_options
@click.option("--mesh-resolution", type=click.IntRange(2, 64), default=None,
              help="Samples per patch side of the mesh the rays hit first [default: about 600k triangles, 2 to 8]; "
                   "the hit is then moved onto the exact patch by Newton steps.")
@surface_options
@input_options
@click.option("-q", "--quiet", is_flag=True, help="No progress bars (they only appear on a terminal anyway).")
@friendly_errors
@with_formats
def render_command(input_path, images, camera, size, atlas, tile, colours, mesh_resolution, surface, inputs, quiet):
    """Render the surface of INPUT (a mesh: {mesh_inputs}) or PATCHES ({patch_inputs}) to images.

    Each pixel's curvature is exact: the pixel's ray hits a tessellation, the hit
    triangle gives the patch and an approximate (u, v), Newton steps move it onto
    the patch, and curvature, normal and position are evaluated there. The
    default camera frames the whole surface. Give at least one of -o (EXR),
    --png and --zebra.
    """
    check_outputs(images, colours.value_range)
    width, height = parse_size(size)
    if not atlas:
        check_image_size(width * height)
    progress = Progress(quiet)
    patches = read_patches(input_path, surface, inputs, quiet, progress)
    if colours.stripe_axis is not None and not np.linalg.norm(colours.stripe_axis) > 0:
        raise click.BadParameter("--stripe-axis must not be the zero vector")
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="embreex is not installed")  # a note below says it
        if atlas:
            image = atlas_image(patches, tile, width, height, camera, progress)
        else:
            image = view_image(patches, mesh_resolution, width, height, camera, progress)
    if not quiet:
        image_notes(image)
    picture, rgb, colour_range = curvature_picture(image, colours.quantity, colours.colormap, colours.value_range)
    write_atomically(images.exr, input_path, progress,
                     lambda tmp: write_exr(tmp, exr_channels(image, rgb), exr_attributes(image, colours.quantity,
                                                                                         colour_range)))
    write_atomically(images.png, input_path, progress, lambda tmp: write_png(tmp, picture))
    write_atomically(images.zebra, input_path, progress,
                     lambda tmp: write_png(tmp, zebra_picture(image, colours.stripes, colours.stripe_axis)))
    progress.done()
