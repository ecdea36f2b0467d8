"""Tests of the IGES 5.3 writer (c1surf.io.patches.iges_writer).

Record structure and entity contents are checked by a small independent
parser; geometry is checked by reading the files back with Open CASCADE
(``OCP``, from the ``cadquery-ocp`` test dependency).  When OCP is missing
the Open CASCADE tests FAIL (they are not skipped).
"""

from __future__ import annotations

import math
import os
import time

import numpy as np
import pytest

from c1surf.io.patches.iges_numbers import format_reals
from c1surf.io.patches.iges_writer import UNITS, bezier_patches_to_surfaces, write_iges

try:  # Open CASCADE; missing -> the OCC tests fail with this message
    from OCP.BRep import BRep_Tool
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeSolid, BRepBuilderAPI_Sewing
    from OCP.BRepCheck import BRepCheck_Analyzer
    from OCP.BRepGProp import BRepGProp
    from OCP.BRepTools import BRepTools
    from OCP.GProp import GProp_GProps
    from OCP.IFSelect import IFSelect_RetDone
    from OCP.IGESControl import IGESControl_Reader
    from OCP.ShapeAnalysis import ShapeAnalysis_FreeBounds
    from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_SHELL
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopLoc import TopLoc_Location
    from OCP.TopoDS import TopoDS

    _OCP_ERROR: Exception | None = None
except ImportError as exc:  # pragma: no cover - exercised only without OCP
    _OCP_ERROR = exc


def _need_ocp() -> None:
    if _OCP_ERROR is not None:
        pytest.fail(
            f"Open CASCADE binding 'OCP' is not importable ({_OCP_ERROR}); "
            "install the test extra: pip install -e '.[test]' (cadquery-ocp)",
            pytrace=False,
        )


# ----------------------------------------------------------------------------
# reference evaluation (numpy)


def _bernstein(d: int, t: float) -> np.ndarray:
    return np.array([math.comb(d, i) * t**i * (1 - t) ** (d - i) for i in range(d + 1)])


def _bspline_basis(knots: np.ndarray, deg: int, t: float) -> np.ndarray:
    """Cox-de Boor; at the right end the last non-empty span is used."""
    knots = np.asarray(knots, dtype=float)
    n = knots.size - deg - 1
    if t >= knots[n]:
        span = int(np.nonzero(knots[:-1] < knots[n])[0][-1])
    else:
        span = int(np.searchsorted(knots, t, side="right") - 1)
    N = np.zeros(knots.size - 1)
    N[span] = 1.0
    for p in range(1, deg + 1):
        M = np.zeros(knots.size - 1 - p)
        for i in range(M.size):
            a = knots[i + p] - knots[i]
            b = knots[i + p + 1] - knots[i + 1]
            if a > 0:
                M[i] += (t - knots[i]) / a * N[i]
            if b > 0:
                M[i] += (knots[i + p + 1] - t) / b * N[i + 1]
        N = M
    return N[:n]


def _evaluate(surf: dict, u: float, v: float) -> np.ndarray:
    P = np.asarray(surf["points"], dtype=float)
    W = np.ones(P.shape[:2]) if surf.get("weights") is None else np.asarray(surf["weights"], float)
    if surf.get("knots_u") is None:
        bu = _bernstein(P.shape[0] - 1, u)
        bv = _bernstein(P.shape[1] - 1, v)
    else:
        du, dv = surf["degree"]
        bu = _bspline_basis(surf["knots_u"], du, u)
        bv = _bspline_basis(surf["knots_v"], dv, v)
    B = np.outer(bu, bv) * W
    return np.einsum("ij,ijk->k", B, P) / B.sum()


def _param_range(surf: dict) -> tuple[float, float, float, float]:
    if surf.get("knots_u") is None:
        return 0.0, 1.0, 0.0, 1.0
    du, dv = surf["degree"]
    nu, nv = np.asarray(surf["points"]).shape[:2]
    ku, kv = surf["knots_u"], surf["knots_v"]
    return float(ku[du]), float(ku[nu]), float(kv[dv]), float(kv[nv])


# ----------------------------------------------------------------------------
# test data


def _sphere_point(theta: np.ndarray, phi: np.ndarray, r: float = 2.0) -> np.ndarray:
    theta, phi = np.broadcast_arrays(theta, phi)
    return np.stack(
        [r * np.sin(theta) * np.cos(phi), r * np.sin(theta) * np.sin(phi), r * np.cos(theta)], axis=-1
    )


def _sphere_patches(deg: int, nt: int = 3, nph: int = 6, noise: float = 0.0, seed: int = 0) -> np.ndarray:
    """Grid of patches whose control points sample a sphere (shared edges)."""
    rng = np.random.default_rng(seed)
    th = np.linspace(0.25, math.pi - 0.25, nt * deg + 1)
    ph = np.linspace(0.0, 2 * math.pi, nph * deg + 1)
    G = _sphere_point(th[:, None], ph[None, :])  # (nt*deg+1, nph*deg+1, 3)
    out = []
    for a in range(nt):
        for b in range(nph):
            out.append(G[a * deg : (a + 1) * deg + 1, b * deg : (b + 1) * deg + 1])
    P = np.array(out)
    return P + noise * rng.standard_normal(P.shape)


def _mixed_surfaces() -> list[dict]:
    rng = np.random.default_rng(42)
    surfs: list[dict] = []
    quad = _sphere_patches(2, noise=0.01, seed=1)
    cub = _sphere_patches(3, noise=0.01, seed=2)
    # interleave biquadratic and bicubic patches
    for i in range(max(len(quad), len(cub))):
        if i < len(quad):
            surfs.append({"points": quad[i], "weights": None})
        if i < len(cub):
            surfs.append({"points": cub[i], "weights": None})
    # random rational bicubic and biquadratic patches with non-unit weights
    for d in (3, 2):
        P = rng.standard_normal((d + 1, d + 1, 3)) * 5 + 10
        W = rng.uniform(0.5, 2.0, (d + 1, d + 1))
        surfs.append({"points": P, "weights": W})
    # a non-square Bezier patch (degree 3 x 2) with tiny and huge coordinates
    P = rng.standard_normal((4, 3, 3))
    P[0, 0] = [1e-7, -3.5e-12, 0.0]
    P[1, 2] = [123456.789, -1e-5, 2.5e-4]
    surfs.append({"points": P, "weights": None})
    # a merged B-spline piece: bicubic x biquadratic, interior knots, range
    # not [0,1]
    Pb = rng.standard_normal((6, 5, 3)) + np.array([0.0, 0.0, 20.0])
    surfs.append(
        {
            "points": Pb,
            "weights": rng.uniform(0.8, 1.25, (6, 5)),
            "knots_u": np.array([0, 0, 0, 0, 0.5, 1.25, 2, 2, 2, 2], dtype=float),
            "knots_v": np.array([1, 1, 1, 2, 3, 4, 4, 4], dtype=float),
            "degree": (3, 2),
        }
    )
    return surfs


def _cube_sphere(deg: int, radius: float = 3.0) -> list[dict]:
    """Six Bezier patches (one per cube face) of a closed, sphere-like
    surface.  Control points come from a cube grid mapped onto a sphere; the
    boundary points of neighbouring faces are computed from identical cube
    points, so shared edges agree bit for bit."""
    t = np.linspace(-1.0, 1.0, deg + 1)
    surfs = []
    for axis in range(3):
        for sign in (-1.0, 1.0):
            P = np.empty((deg + 1, deg + 1, 3))
            a1, a2 = [k for k in range(3) if k != axis]
            for i in range(deg + 1):
                for j in range(deg + 1):
                    c = np.empty(3)
                    c[axis] = sign
                    c[a1] = t[i]
                    c[a2] = t[j]
                    P[i, j] = radius * c / np.linalg.norm(c)
            surfs.append({"points": P, "weights": None})
    return surfs


# ----------------------------------------------------------------------------
# an independent IGES parser for the checks


def _split_params(text: str) -> list[str]:
    """Split free-format parameters (',' / ';'), Hollerith-aware."""
    out, i, n, cur = [], 0, len(text), ""
    while i < n:
        ch = text[i]
        if ch == " " and not cur:  # blanks between parameters
            i += 1
            continue
        if ch.isdigit() and not cur:
            j = i
            while j < n and text[j].isdigit():
                j += 1
            if j < n and text[j] == "H":
                ln = int(text[i:j])
                out.append(text[j + 1 : j + 1 + ln])
                i = j + 1 + ln
                assert text[i] in ",;", "Hollerith not followed by a delimiter"
                if text[i] == ";":
                    return out
                i += 1
                continue
        if ch in ",;":
            out.append(cur)
            cur = ""
            if ch == ";":
                return out
        else:
            cur += ch
        i += 1
    raise AssertionError("no record delimiter")


def _parse_iges(data: bytes) -> dict:
    assert data.endswith(b"\n")
    text = data.decode("ascii")
    lines = text.split("\n")[:-1]
    for ln in lines:
        assert len(ln) == 80, f"record of {len(ln)} columns: {ln!r}"
    letters = "".join(ln[72] for ln in lines)
    # sections in order, each at least as required, exactly one T at the end
    import re

    assert re.fullmatch(r"S+G+D*P*T", letters), letters
    sections: dict[str, list[str]] = {c: [ln for ln in lines if ln[72] == c] for c in "SGDPT"}
    for c, recs in sections.items():
        seqs = [int(r[73:80]) for r in recs]
        assert seqs == list(range(1, len(recs) + 1)), f"bad sequence numbers in {c}"
        assert all(r[73:80].isdigit() for r in recs)
    term = sections["T"][0]
    assert term[:32] == "S%07dG%07dD%07dP%07d" % tuple(len(sections[c]) for c in "SGDP")
    assert term[32:72] == " " * 40

    gtext = "".join(r[:72] for r in sections["G"])
    gparams = _split_params(gtext)

    D, P = sections["D"], sections["P"]
    assert len(D) % 2 == 0
    ents = []
    next_p = 1
    for k in range(0, len(D), 2):
        l1, l2 = D[k], D[k + 1]
        seq = k + 1
        etype = int(l1[0:8])
        assert int(l2[0:8]) == etype
        ptr, cnt = int(l1[8:16]), int(l2[24:32])
        assert ptr == next_p, "PD entries must follow DE order, without gaps"
        next_p += cnt
        for f in range(2, 8):
            assert l1[8 * f : 8 * f + 8].strip() in ("", "0")
        status = l1[64:72]
        assert status.isdigit() and len(status) == 8
        form = int(l2[32:40])
        recs = P[ptr - 1 : ptr - 1 + cnt]
        assert len(recs) == cnt
        body = ""
        for r in recs:
            assert r[64] == " "
            assert int(r[65:72]) == seq, "PD back pointer does not match the DE"
            data_ = r[:64].rstrip()
            assert " " not in data_
            # wrapped only at delimiters: no number split across records
            assert data_[-1] in ",;", f"record does not end at a delimiter: {r!r}"
            body += data_
        assert body.count(";") == 1 and body.endswith(";")
        toks = body[:-1].split(",")
        assert int(toks[0]) == etype
        ents.append(
            dict(
                seq=seq,
                type=etype,
                form=form,
                status=status,
                label=l2[56:64].strip(),
                subscript=l2[64:72].strip(),
                params=toks[1:],
            )
        )
    assert next_p == len(P) + 1, "P records not covered by the DE pointers"
    return dict(start=sections["S"], gparams=gparams, entities=ents, nlines=len(lines))


def _real(tok: str) -> float:
    assert "." in tok, f"real without decimal point: {tok}"
    return float(tok.replace("D", "E"))


def _check_entity_128(params: list[str], surf: dict) -> None:
    P = np.asarray(surf["points"], dtype=float)
    nu, nv = P.shape[:2]
    if surf.get("knots_u") is None:
        du, dv = nu - 1, nv - 1
        ku = np.r_[np.zeros(du + 1), np.ones(du + 1)]
        kv = np.r_[np.zeros(dv + 1), np.ones(dv + 1)]
    else:
        du, dv = surf["degree"]
        ku, kv = np.asarray(surf["knots_u"], float), np.asarray(surf["knots_v"], float)
    W = np.ones((nu, nv)) if surf.get("weights") is None else np.asarray(surf["weights"], float)
    ints = [int(t) for t in params[:9]]
    k1, k2, m1, m2, p1, p2, p3, p4, p5 = ints
    assert (k1, k2, m1, m2) == (nu - 1, nv - 1, du, dv)
    assert p3 == (1 if np.all(W == W.flat[0]) else 0)
    assert (p4, p5) == (0, 0)
    assert p1 == 0 and p2 == 0  # none of the test surfaces is closed
    vals = np.array([_real(t) for t in params[9:]])
    n1, n2 = k1 + m1 + 2, k2 + m2 + 2
    ncp = nu * nv
    assert vals.size == n1 + n2 + ncp + 3 * ncp + 4
    # exact round trip of every number
    np.testing.assert_array_equal(vals[:n1], ku)
    np.testing.assert_array_equal(vals[n1 : n1 + n2], kv)
    o = n1 + n2
    np.testing.assert_array_equal(vals[o : o + ncp], W.T.ravel())  # u fastest
    o += ncp
    np.testing.assert_array_equal(vals[o : o + 3 * ncp].reshape(nv, nu, 3), P.transpose(1, 0, 2))
    np.testing.assert_array_equal(vals[-4:], _param_range(surf))


# ----------------------------------------------------------------------------
# format / structure tests (no Open CASCADE needed)


def testformat_reals_round_trip_exactly():
    rng = np.random.default_rng(7)
    x = np.concatenate(
        [
            rng.standard_normal(50_000) * 10.0 ** rng.integers(-12, 20, 50_000),
            rng.standard_normal(20_000),
            rng.integers(-(10**6), 10**6, 5_000) / 64.0,
            10.0 ** np.arange(-6, 18),
            -(10.0 ** np.arange(-6, 18)),
            np.nextafter(10.0 ** np.arange(-6, 18), 0),
            np.nextafter(10.0 ** np.arange(-6, 18), np.inf),
            [0.0, -0.0, 0.1, 0.2, 0.1 + 0.2, 1 / 3, 1e-4, 9.999999999999999e-05, 1e16,
             9999999999999998.0, 5e-324, 2.2250738585072014e-308, 1.7976931348623157e308],
        ]
    )
    chars, off, lens = format_reals(x)
    assert lens.max() <= 24
    longer = 0
    for v, c, o, n in zip(x.tolist(), chars, off.tolist(), lens.tolist()):
        s = c[o : o + n].tobytes().decode("ascii")
        assert set(s) <= set("0123456789.-+D"), s
        assert "." in s and s.count("D") <= 1
        assert float(s.replace("D", "E")) == v, (repr(v), s)
        longer += len(s) > len(repr(v))
    assert longer < 0.05 * x.size  # close to shortest (repr) length


def test_structure_and_contents(tmp_path):
    surfs = _mixed_surfaces()
    path = tmp_path / "mixed.igs"
    write_iges(path, surfs, author="Tester", organization="c1surf org")
    doc = _parse_iges(path.read_bytes())
    ents = doc["entities"]
    assert len(ents) == len(surfs) + 1
    for i, (e, s) in enumerate(zip(ents, surfs)):
        assert e["type"] == 128 and e["form"] == 0
        assert e["status"] == "00020000"  # logically dependent: group member
        assert e["subscript"] == str(i + 1)
        assert e["label"] == ("BSPLINE" if s.get("knots_u") is not None else "BEZIER")
        _check_entity_128(e["params"], s)
    grp = ents[-1]
    assert (grp["type"], grp["form"], grp["status"]) == (402, 7, "00000000")
    assert [int(t) for t in grp["params"]] == [len(surfs)] + [e["seq"] for e in ents[:-1]]


def test_global_section(tmp_path):
    surfs = bezier_patches_to_surfaces(_sphere_patches(3))
    path = tmp_path / "sphere.igs"
    write_iges(
        path,
        surfs,
        units="in",
        author="Ada, Lovelace; et al.",
        organization="Org",
        timestamp=1_795_000_000,
    )
    g = _parse_iges(path.read_bytes())["gparams"]
    assert len(g) == 26
    assert g[0] == "," and g[1] == ";"
    assert g[2] == "sphere" and g[3] == "sphere.igs" and g[4] == "c1surf"
    assert g[5].startswith("c1surf ")
    assert [int(t) for t in g[6:11]] == [32, 38, 6, 308, 15]
    assert g[11] == "sphere"
    assert _real(g[12]) == 1.0
    assert int(g[13]) == 1 and g[14] == "INCH"
    assert int(g[15]) == 1 and _real(g[16]) > 0
    assert g[17] == "20261118.110640"  # 1_795_000_000 s after the epoch, UTC
    pts = np.concatenate([np.asarray(s["points"]).reshape(-1, 3) for s in surfs])
    diag = np.linalg.norm(pts.max(0) - pts.min(0))
    assert _real(g[18]) == pytest.approx(1e-9 * diag)
    assert _real(g[19]) == np.abs(pts).max()
    assert g[20] == "Ada, Lovelace; et al." and g[21] == "Org"
    assert int(g[22]) == 11 and int(g[23]) == 0
    assert g[24] == g[17]
    assert g[25] == ""


def test_units_and_errors(tmp_path):
    p = np.zeros((2, 2, 3))
    p[1, :, 0] = 1
    p[:, 1, 1] = 1
    for name, (flag, uname) in UNITS.items():
        path = tmp_path / f"u_{name}.igs"
        write_iges(path, [{"points": p, "weights": None}], units=name)
        g = _parse_iges(path.read_bytes())["gparams"]
        assert int(g[13]) == flag and g[14] == uname
    with pytest.raises(ValueError):
        write_iges(tmp_path / "x.igs", [{"points": p}], units="furlong")
    with pytest.raises(ValueError):
        write_iges(tmp_path / "x.igs", [{"points": np.zeros((3, 3))}])
    with pytest.raises(ValueError):
        write_iges(tmp_path / "x.igs", [{"points": p, "weights": -np.ones((2, 2))}])
    with pytest.raises(ValueError):
        write_iges(tmp_path / "x.igs", [{"points": p, "weights": np.ones((3, 2))}])
    bad = p.copy()
    bad[0, 0, 0] = np.nan
    with pytest.raises(ValueError):
        write_iges(tmp_path / "x.igs", [{"points": bad}])
    with pytest.raises(ValueError):  # knot count
        write_iges(
            tmp_path / "x.igs",
            [{"points": p, "knots_u": [0, 0, 1], "knots_v": [0, 0, 1, 1], "degree": (1, 1)}],
        )
    with pytest.raises(ValueError):  # decreasing knots
        write_iges(
            tmp_path / "x.igs",
            [{"points": p, "knots_u": [0, 0, 1, 0.5], "knots_v": [0, 0, 1, 1], "degree": (1, 1)}],
        )


def test_group_false_and_empty(tmp_path):
    surfs = bezier_patches_to_surfaces(_sphere_patches(2))
    path = tmp_path / "nogroup.igs"
    write_iges(path, surfs, group=False)
    ents = _parse_iges(path.read_bytes())["entities"]
    assert len(ents) == len(surfs)
    assert all(e["type"] == 128 and e["status"] == "00000000" for e in ents)
    path = tmp_path / "empty.igs"
    write_iges(path, [])
    doc = _parse_iges(path.read_bytes())
    assert doc["entities"] == [] and len(doc["gparams"]) == 26


def test_deterministic(tmp_path, monkeypatch):
    surfs = _mixed_surfaces()
    monkeypatch.delenv("SOURCE_DATE_EPOCH", raising=False)
    a, b = tmp_path / "a.igs", tmp_path / "b.igs"
    write_iges(a, surfs, file_name="model.igs")
    write_iges(b, surfs, file_name="model.igs")
    assert a.read_bytes() == b.read_bytes()
    assert _parse_iges(a.read_bytes())["gparams"][17] == "19700101.000000"
    monkeypatch.setenv("SOURCE_DATE_EPOCH", "1700000000")
    write_iges(b, surfs, file_name="model.igs")
    assert _parse_iges(b.read_bytes())["gparams"][17] == "20231114.221320"
    # rewriting over a longer file leaves no stale tail
    write_iges(b, surfs[:2], file_name="model.igs")
    _parse_iges(b.read_bytes())


def test_bezier_patches_to_surfaces():
    P = _sphere_patches(3)
    s = bezier_patches_to_surfaces(P)
    assert len(s) == len(P) and s[0]["weights"] is None
    np.testing.assert_array_equal(s[5]["points"], P[5])
    W = np.full(P.shape[:3], 2.0)
    s = bezier_patches_to_surfaces(P, W)
    np.testing.assert_array_equal(s[3]["weights"], W[3])
    with pytest.raises(ValueError):
        bezier_patches_to_surfaces(P[..., :2])
    with pytest.raises(ValueError):
        bezier_patches_to_surfaces(P, W[:, :2])


def test_closed_flags(tmp_path):
    # a patch whose first and last u-rows coincide is closed in u (PROP1)
    th = np.linspace(0, 2 * np.pi, 4)
    P = np.zeros((4, 3, 3))
    for j, z in enumerate((0.0, 1.0, 2.0)):
        P[:, j] = np.stack([np.cos(th), np.sin(th), np.full(4, z)], axis=1)
    P[-1] = P[0]
    path = tmp_path / "closed.igs"
    write_iges(path, [{"points": P}])
    e = _parse_iges(path.read_bytes())["entities"][0]
    assert [int(t) for t in e["params"][4:9]] == [1, 0, 1, 0, 0]


def test_write_speed(tmp_path):
    P = np.random.default_rng(3).standard_normal((20_000, 4, 4, 3)) * 50
    t0 = time.perf_counter()
    write_iges(tmp_path / "big.igs", bezier_patches_to_surfaces(P))
    dt = time.perf_counter() - t0
    # about 0.8 s here (100k bicubic patches: about 4 s); generous bound
    assert dt < 15.0
    size = os.path.getsize(tmp_path / "big.igs")
    assert size % 81 == 0


# ----------------------------------------------------------------------------
# Open CASCADE read-back


def _occ_read(path, expect_roots: int | None = None):
    reader = IGESControl_Reader()
    status = reader.ReadFile(str(path))
    assert status == IFSelect_RetDone
    # Open CASCADE's load check: no failure and no warning on any entity
    assert reader.WS().ModelCheckList().IsEmpty(False)
    if expect_roots is not None:
        assert reader.NbRootsForTransfer() == expect_roots
    reader.TransferRoots()
    assert reader.NbShapes() >= 1
    return reader, reader.OneShape()


def _faces(shape) -> list:
    out = []
    exp = TopExp_Explorer(shape, TopAbs_FACE)
    while exp.More():
        out.append(TopoDS.Face(exp.Current()))
        exp.Next()
    return out


def _count(shape, kind) -> int:
    n = 0
    exp = TopExp_Explorer(shape, kind)
    while exp.More():
        n += 1
        exp.Next()
    return n


def _compare_faces(faces, surfs, scale: float = 1.0) -> None:
    """``scale``: Open CASCADE converts file units to millimetres."""
    assert len(faces) == len(surfs)
    pts = np.concatenate([np.asarray(s["points"], float).reshape(-1, 3) for s in surfs])
    tol = 1e-9 * scale * float(np.linalg.norm(pts.max(0) - pts.min(0)))
    params = [(0.0, 0.0), (1.0, 1.0), (0.0, 1.0), (1.0, 0.0), (0.5, 0.5), (0.13, 0.71), (0.9, 0.27)]
    for face, surf in zip(faces, surfs):
        loc = TopLoc_Location()
        geom = BRep_Tool.Surface_s(face, loc)
        assert loc.IsIdentity()
        u0, u1, v0, v1 = _param_range(surf)
        # the parameter range is kept unchanged by the reader
        assert BRepTools.UVBounds_s(face) == pytest.approx((u0, u1, v0, v1), abs=1e-12)
        for a, b in params:
            u, v = u0 + a * (u1 - u0), v0 + b * (v1 - v0)
            p = geom.Value(u, v)
            got = np.array([p.X(), p.Y(), p.Z()])
            np.testing.assert_allclose(got, scale * _evaluate(surf, u, v), rtol=0, atol=tol)


def test_occ_read_back_mixed(tmp_path):
    _need_ocp()
    surfs = _mixed_surfaces()
    path = tmp_path / "mixed.igs"
    write_iges(path, surfs)
    reader, shape = _occ_read(path, expect_roots=1)  # the group is the only root
    gs = reader.IGESModel().GlobalSection()
    assert gs.IGESVersion() == 11 and gs.UnitFlag() == 2
    assert gs.UnitName().ToCString() == "MM"
    assert gs.AuthorName().ToCString() == "c1surf"
    assert gs.Date().ToCString() == "19700101.000000"
    model = reader.IGESModel()
    assert model.NbEntities() == len(surfs) + 1
    grp = model.Entity(model.NbEntities())
    assert (grp.TypeNumber(), grp.FormNumber(), grp.NbEntities()) == (402, 7, len(surfs))
    assert model.Entity(1).SubordinateStatus() == 2
    faces = _faces(shape)
    _compare_faces(faces, surfs)
    # rational flags survive: the rational patches come back rational
    for face, s in zip(faces, surfs):
        geom = BRep_Tool.Surface_s(face)
        rational = s.get("weights") is not None and not np.all(s["weights"] == s["weights"].flat[0])
        assert geom.IsURational() or geom.IsVRational() or not rational


def test_occ_ordered_group(tmp_path):
    _need_ocp()
    surfs = bezier_patches_to_surfaces(_sphere_patches(2, nt=2, nph=3))
    path = tmp_path / "ordered.igs"
    write_iges(path, surfs, group="ordered")
    ents = _parse_iges(path.read_bytes())["entities"]
    assert (ents[-1]["type"], ents[-1]["form"]) == (402, 15)
    reader, shape = _occ_read(path, expect_roots=1)
    grp = reader.IGESModel().Entity(len(surfs) + 1)
    assert (grp.TypeNumber(), grp.FormNumber()) == (402, 15)
    _compare_faces(_faces(shape), surfs)
    with pytest.raises(ValueError):
        write_iges(path, surfs, group="sorted")


def test_occ_read_back_without_group(tmp_path):
    _need_ocp()
    surfs = bezier_patches_to_surfaces(_sphere_patches(3, noise=0.05, seed=5))
    path = tmp_path / "nogroup.igs"
    write_iges(path, surfs, group=False, units="m")
    reader, shape = _occ_read(path, expect_roots=len(surfs))
    assert reader.IGESModel().GlobalSection().UnitFlag() == 6
    # the file is in metres; Open CASCADE hands the shape back in millimetres
    _compare_faces(_faces(shape), surfs, scale=1000.0)


def test_occ_rational_quarter_cylinder(tmp_path):
    """Exact circle arcs need the weights: every point is at radius r."""
    _need_ocp()
    r, h = 4.0, 3.0
    w = math.sqrt(0.5)
    P = np.zeros((3, 2, 3))
    for i, (x, y) in enumerate([(r, 0.0), (r, r), (0.0, r)]):
        P[i, 0] = [x, y, 0.0]
        P[i, 1] = [x, y, h]
    W = np.array([[1.0, 1.0], [w, w], [1.0, 1.0]])
    path = tmp_path / "cyl.igs"
    write_iges(path, [{"points": P, "weights": W}])
    _, shape = _occ_read(path)
    (face,) = _faces(shape)
    geom = BRep_Tool.Surface_s(face)
    for u in np.linspace(0, 1, 11):
        for v in (0.0, 0.4, 1.0):
            p = geom.Value(float(u), float(v))
            assert math.hypot(p.X(), p.Y()) == pytest.approx(r, abs=1e-12)
            assert p.Z() == pytest.approx(v * h, abs=1e-12)


@pytest.mark.parametrize("deg", [2, 3])
def test_occ_closed_surface_sews_to_one_closed_shell(tmp_path, deg):
    _need_ocp()
    surfs = _cube_sphere(deg)
    path = tmp_path / f"cubesphere{deg}.igs"
    write_iges(path, surfs)
    _, shape = _occ_read(path, expect_roots=1)
    faces = _faces(shape)
    _compare_faces(faces, surfs)

    sew = BRepBuilderAPI_Sewing(1e-7)
    for f in faces:
        sew.Add(f)
    sew.Perform()
    sewed = sew.SewedShape()
    assert sew.NbFreeEdges() == 0
    assert sew.NbMultipleEdges() == 0
    assert _count(sewed, TopAbs_SHELL) == 1
    assert _count(sewed, TopAbs_FACE) == 6
    free = ShapeAnalysis_FreeBounds(sewed, 1e-7, False, False)
    assert _count(free.GetClosedWires(), TopAbs_EDGE) == 0
    assert _count(free.GetOpenWires(), TopAbs_EDGE) == 0
    assert BRepCheck_Analyzer(sewed).IsValid()

    exp = TopExp_Explorer(sewed, TopAbs_SHELL)
    shell = TopoDS.Shell(exp.Current())
    assert BRep_Tool.IsClosed_s(shell)
    solid = BRepBuilderAPI_MakeSolid(shell).Solid()
    props = GProp_GProps()
    BRepGProp.VolumeProperties_s(solid, props)
    vol = abs(props.Mass())
    # inside the radius-3 ball (control points lie on it), far from empty
    assert 0.5 * (4 / 3) * math.pi * 27 < vol < (4 / 3) * math.pi * 27
