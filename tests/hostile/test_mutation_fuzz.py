"""The fast run of the mutation fuzzer (issue 42): 240 seeded cases over every reader and every command that
reads a file, in this process (``fuzzing.run_case``; STEP's Open CASCADE runs in c1surf's own child process).
``make fuzz`` runs 20,000 more in processes a crash cannot take down (``tests/hostile/fuzzing.py``)."""
from __future__ import annotations

import pytest

from fuzzing import case_plan, make_seeds, run_case

pytestmark = pytest.mark.filterwarnings("error")  # pytest would record a warning that stderr shows: make it fail

CASES = 240
CHUNKS = 8


@pytest.fixture(scope="module")
def seeds(tmp_path_factory):
    return make_seeds(tmp_path_factory.mktemp("fuzz") / "seeds")


def test_the_plan_covers_every_file_and_command():
    plans = {case_plan(case) for case in range(CASES)}
    assert {name for name, _ in plans} >= {"box.obj", "box_ascii.ply", "box_binary.ply", "box_ascii.stl",
                                            "box_binary.stl", "box.off", "box.usda", "box.usdc", "box.json",
                                            "box.npz", "box.igs", "box.step"}
    commands = {command for _, command in plans}
    assert commands >= {"convert", "check", "measure", "tessellate", "inspect", "diff", "render", "batch"}


@pytest.mark.parametrize("chunk", range(CHUNKS))
def test_mutated_inputs_keep_the_promise(seeds, tmp_path, chunk):
    failures = []
    for case in range(chunk, CASES, CHUNKS):
        failure, what, _ = run_case(case, seeds, tmp_path / "work")
        if failure:
            failures.append(f"{what}: {failure}")
    assert not failures, "\n".join(failures)
