"""The CAD writers' memory (``io.registry`` Format.memory, ``io.patches.formats``): a STEP or IGES file that would
not fit in memory is refused before anything is written, in one line that says what to do."""
from __future__ import annotations

import pytest
from click.testing import CliRunner

from c1surf.cli.main import main
from c1surf.io.errors import OutputError
from c1surf.io.patches.formats import (MEMORY_LIMIT_VARIABLE, available_memory, check_patch_writer_memory,
                                       load_patch_set, patch_writer_memory, write_patch_set)

from conftest import SAMPLES


def test_the_estimate_grows_with_the_patches_and_only_cad_formats_are_modelled():
    step = [patch_writer_memory(".step", n) for n in (0, 1000, 100_000)]
    assert 0 < step[0] < step[1] < step[2] and step[2] > 1 << 30  # 100,000 patches: gigabytes (measured)
    assert 0 < patch_writer_memory(".igs", 100_000) < step[2]
    assert patch_writer_memory(".json", 10**7) == patch_writer_memory(".npz", 10**7) == 0


def test_guard_refuses_with_what_to_do_and_honours_the_limit(tmp_path, monkeypatch):
    with pytest.raises(OutputError) as error:
        check_patch_writer_memory(tmp_path / "x.step", 100_000, available=1 << 30)
    message = str(error.value)
    assert message.startswith(f"{tmp_path / 'x.step'}: writing 100000 patches as STEP would need about ")
    assert "`c1surf fit`" in message and "--force" in message and "\n" not in message
    check_patch_writer_memory(tmp_path / "x.json", 10**8, available=1 << 20)  # not modelled: never refused
    check_patch_writer_memory(tmp_path / "x.step", 10, available=8 << 30)
    monkeypatch.setenv(MEMORY_LIMIT_VARIABLE, "300M")
    assert available_memory() == 300 << 20
    patch_set = load_patch_set(SAMPLES.parent / "tests" / "golden" / "cube.json")
    with pytest.raises(OutputError):  # the writer itself checks first: nothing is written
        write_patch_set(tmp_path / "c.step", patch_set)
    assert not (tmp_path / "c.step").exists()
    write_patch_set(tmp_path / "c.step", patch_set, force=True)  # or not, with force
    with pytest.raises(OutputError):
        check_patch_writer_memory(tmp_path / "c.igs", 10**6)


def test_convert_refuses_a_cad_output_that_would_not_fit_before_writing_anything(tmp_path):
    out, step = tmp_path / "out.ply", tmp_path / "p.step"
    args = ["convert", str(SAMPLES / "cube.obj"), "-o", str(out), "--patches", str(step), "-r", "2", "-q"]
    result = CliRunner().invoke(main, args, env={MEMORY_LIMIT_VARIABLE: "100M"})
    assert result.exit_code == 1
    [line] = result.stderr.strip().splitlines()
    assert line.startswith(f"c1surf: error: {step}: writing 96 patches as STEP would need about ")
    assert "fewer faces (`c1surf fit`" in line
    assert not out.exists() and not step.exists() and not [p for p in tmp_path.iterdir() if p.name.startswith(".tmp")]
    pytest.importorskip("OCP")
    result = CliRunner().invoke(main, args + ["--force"], env={MEMORY_LIMIT_VARIABLE: "100M"})
    assert result.exit_code == 0 and out.exists() and step.exists()  # --force writes anyway
