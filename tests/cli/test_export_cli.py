"""rtaw-export: the command line, its one-line errors and exit statuses."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from rtaw_marl.cli.export import main, parse
from rtaw_marl.errors import ConfigError
from rtaw_marl.policies.export import ExportConfig
from rtaw_marl.policies.pretrained.registry import pretrained_path
from rtaw_marl.utils.runs import claim_file

pytestmark = pytest.mark.integration

RTAW_EXPORT = Path(sys.executable).with_name("rtaw-export")


def _exit(argv: list[str], capsys) -> tuple[int, str, str]:
    with pytest.raises(SystemExit) as exc:
        main(argv)
    out, err = capsys.readouterr()
    return exc.value.code, out, err


def test_export_to_torchscript_reports_the_check(tmp_path: Path, capsys) -> None:
    out = tmp_path / "rtaw.pt"
    argv = ["A_astar_m10", f"output={out}", "num_robots=7", "queue_len=4", "num_tasks=20"]
    code, stdout, err = _exit(argv, capsys)
    assert code == 0, err
    assert f"A_astar_m10 -> {out}" in stdout
    assert "checked: 20 decisions" in stdout
    assert "same choice at 20/20" in stdout
    # The output was held while it was made (claim_file): its lock is gone.
    assert sorted(p.name for p in tmp_path.iterdir()) == ["rtaw.pt", "rtaw.pt.json"]
    check = json.loads(Path(f"{out}.json").read_text())["check"]
    assert check["shapes"]["robots"] == [20, 7, 3]
    assert check["shapes"]["tasks"] == [20, 4, 6]


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["nope", "output=x.onnx"], "'nope' is neither a checkpoint file nor a shipped"),
        (["A_astar_m10", "output=x.txt"], "output must end in .pt (TorchScript) or .onnx"),
        (["A_astar_m10"], "output=FILE.pt (TorchScript) or output=FILE.onnx (ONNX) is needed"),
        (["A_astar_m10", "output=x.pt", "robots=3"], "unknown key 'robots'; valid keys: output"),
        (["A_astar_m10", "output=x.pt", "x.onnx"], "expected KEY=VALUE, got 'x.onnx'"),
        (["A_astar_m10", "output=x.pt", "num_robots=ten"], "num_robots must be an integer"),
        (["A_astar_m10", "output=x.pt", "num_tasks=0"], "num_tasks must be an integer >= 1"),
        (
            ["A_astar_m10", "output=x.pt", "atol=-1"],
            "atol must be >= 0 and <= 1, got -1: a "
            "logit difference of 1 already scales a slot's probability by e (2.7)",
        ),
        # inf would switch the logit check off; nan would fail every logit.
        (["A_astar_m10", "output=x.pt", "atol=inf"], "atol must be >= 0 and <= 1, got inf: "),
        (["A_astar_m10", "output=x.pt", "atol=nan"], "atol must be >= 0 and <= 1, got nan: "),
        (["A_astar_m10", "output=x.pt", "atol=2"], "atol must be >= 0 and <= 1, got 2: "),
        # A huge rtol overflows float32 and reports an identical model as disagreeing.
        (
            ["A_astar_m10", "output=x.pt", "rtol=1e308"],
            "rtol must be >= 0 and <= 0.01, got "
            "1e+308: 1% of a logit in the hundreds is several units",
        ),
        (["A_astar_m10", "output=x.pt", "rtol=inf"], "rtol must be >= 0 and <= 0.01, got inf: "),
        (["A_astar_m10", "output=x.pt", "rtol=0.5"], "rtol must be >= 0 and <= 0.01, got 0.5: "),
        (["A_astar_m10", "output=x.pt", "rtol=-0.1"], "rtol must be >= 0 and <= 0.01, got -0.1"),
        (["A_astar_m10", "output=x.pt", "layout=Z"], "unknown layout 'Z'; available: A"),
        ([], "the following arguments are required: policy"),
    ],
)
def test_bad_input_is_one_line_and_exit_2(
    argv: list[str], message: str, tmp_path: Path, capsys, monkeypatch
) -> None:
    monkeypatch.chdir(tmp_path)
    code, _, err = _exit(argv, capsys)
    assert code == 2
    assert err.count("\n") == 1, err
    assert err.startswith("error: ")
    assert message in err
    assert list(tmp_path.iterdir()) == []


def test_the_tolerances_are_checked_for_the_python_api_too() -> None:
    for bad in (float("inf"), np.float64(1e308), -1, "0.1", True):
        with pytest.raises(ConfigError, match=r"^rtol must be (a number )?>= 0 and <= 0.01"):
            ExportConfig(output="a.pt", rtol=bad)  # type: ignore[arg-type]
    with pytest.raises(ConfigError) as info:
        ExportConfig(output="a.pt", atol=np.float32(3.0))  # type: ignore[arg-type]
    assert "got 3:" in str(info.value)
    assert "np." not in str(info.value)
    # The range's ends are allowed.
    assert ExportConfig(atol=0.0, rtol=0.01).rtol == 0.01
    assert ExportConfig(atol=1, rtol=0).atol == 1


@pytest.fixture
def checkpoint(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A training checkpoint, ``ck.pt`` in the working folder ``tmp_path``."""
    monkeypatch.chdir(tmp_path)
    path = tmp_path / "ck.pt"
    shutil.copyfile(pretrained_path("A_astar_m10"), path)
    (tmp_path / "link.pt").symlink_to(path)
    (tmp_path / "sub").mkdir()
    return path


@pytest.mark.parametrize(
    ("source", "output", "written"),
    [
        ("ck.pt", "ck.pt", "the model"),
        ("ck.pt", "link.pt", "the model"),  # a symlink to the checkpoint
        ("link.pt", "ck.pt", "the model"),  # the checkpoint named through a symlink
        ("./ck.pt", "sub/../ck.pt", "the model"),  # another spelling of the same path
        ("{abs}", "ck.pt", "the model"),  # absolute and relative
        ("ck.pt.json", "ck.pt", "its specification ck.pt.json"),  # the sidecar
    ],
)
def test_an_output_that_is_the_checkpoint_is_refused_before_any_work(
    source: str, output: str, written: str, checkpoint: Path, capsys
) -> None:
    """``rtaw-export ck.pt output=ck.pt`` would replace the training checkpoint."""
    if source == "ck.pt.json":  # a checkpoint named like the output's specification
        checkpoint = checkpoint.rename(checkpoint.with_name("ck.pt.json"))
    source = source.format(abs=checkpoint)
    before = sorted(p.name for p in checkpoint.parent.iterdir())
    data = checkpoint.read_bytes()
    code, out, err = _exit([source, f"output={output}"], capsys)
    assert code == 2
    assert out == ""
    assert err.startswith(f"error: output={output}: {written} would replace the checkpoint "
                          "being exported (")  # fmt: skip
    assert err.endswith("); choose another output file\n")
    assert err.count("\n") == 1
    assert checkpoint.read_bytes() == data
    assert sorted(p.name for p in checkpoint.parent.iterdir()) == before  # no lock left


def test_an_output_in_use_is_refused_before_any_work(checkpoint: Path, capsys) -> None:
    out = checkpoint.with_name("model.pt")
    with claim_file(out):
        code, _, err = _exit([str(checkpoint), f"output={out}"], capsys)
    assert code == 2
    assert err == (
        f"error: output={out} is in use by another running process (pid {os.getpid()}); "
        "choose another one\n"
    )
    assert not out.exists()


def test_parse_reads_typed_values_and_none() -> None:
    config = parse(["output=a.onnx", "num_robots=30", "atol=1e-3", "layout=C", "queue_len=none"])
    assert config == ExportConfig(output="a.onnx", num_robots=30, atol=1e-3, layout="C")
    assert config.env_args() == {"layout": "C", "num_robots": 30, "num_tasks": 100}
    with pytest.raises(ConfigError, match="seed is given twice"):
        parse(["seed=1", "seed=2"])


def test_console_script_exits_2_without_a_traceback(tmp_path: Path) -> None:
    proc = subprocess.run(
        [str(RTAW_EXPORT), "generalist", "output=g.onnx"],
        cwd=tmp_path, capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.count("\n") == 1, proc.stderr
    assert "did you mean generalist_plus" in proc.stderr
