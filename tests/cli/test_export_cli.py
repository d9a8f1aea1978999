"""rtaw-export: the command line, its one-line errors and exit statuses."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from rtaw_marl.cli.export import main, parse
from rtaw_marl.errors import ConfigError
from rtaw_marl.policies.export import ExportConfig

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
        (["A_astar_m10", "output=x.pt", "atol=-1"], "atol must be >= 0"),
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
