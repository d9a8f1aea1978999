"""Paths and disks checked before the work: names and paths too long for the filesystem
(with the temporary and lock files written beside them), too little free space, a
folder that cannot be written; and a disk that fills up later, which is one line saying
what was kept."""

from __future__ import annotations

import errno
import os
import re
import shutil
import sys
from pathlib import Path
from typing import Any

import pytest

from rtaw_marl.errors import ConfigError, DiskFullError
from rtaw_marl.models.checkpoint import build_networks, load_checkpoint, save_checkpoint
from rtaw_marl.utils import runs
from rtaw_marl.utils.atomic import atomic_write
from rtaw_marl.utils.runs import (
    LOCK_NAME,
    MIN_FREE_BYTES,
    check_writable_dir,
    claim_file,
    claim_folder,
)

pytestmark = pytest.mark.integration

QUICK = ("sim.num_tasks=30", "progress=false", "policy=[mpdm]", "seeds=[0]")
TRAIN = ("scenario=poc", "progress=false")
NOSPACE = "No space left on device"


def _one_error(result: Any) -> str:
    """The single ``error: ...`` line of a refused run (exit 2, nothing else on stderr)."""
    assert result.code == 2, result.err
    lines = result.err.strip().splitlines()
    assert len(lines) == 1, result.err
    assert lines[0].startswith("error: ")
    return lines[0].removeprefix("error: ")


def _long_path(base: Path, length: int, tail: str = "") -> Path:
    """A path of exactly ``length`` characters under ``base`` (folders of 200), then ``tail``."""
    parts, left = [], length - len(str(base)) - (len(tail) + 1 if tail else 0)
    while left > 0:
        size = min(200, left - 1)
        parts.append("p" * size)
        left -= size + 1
    path = Path(base, *parts, tail) if tail else Path(base, *parts)
    assert len(str(path)) == length
    return path


def _nothing_but_hydra(folder: Path) -> bool:
    """Only Hydra's own run folder was created: the run wrote nothing."""
    return [p.name for p in folder.iterdir()] in ([], ["outputs"])


def _short(text: str, keep: int = 60) -> str:
    return text if len(text) <= 2 * keep + 3 else f"{text[:keep]}...{text[-keep:]}"


# --------------------------------------------------------------------------- lengths
def test_eval_output_in_a_folder_with_a_too_long_name(cli, tmp_path: Path) -> None:
    out = tmp_path / ("a" * 300) / "r.json"
    message = _one_error(cli("eval", *QUICK, f"output={out}"))
    assert message == (
        f"output={_short(str(out))}: the folder name '{'a' * 24}...{'a' * 24}' is 300 "
        "characters; names on its filesystem are at most 255 bytes"
    )
    assert _nothing_but_hydra(tmp_path)


def test_eval_output_path_too_long(cli, tmp_path: Path) -> None:
    out = _long_path(tmp_path, 4453, "r.json")
    message = _one_error(cli("eval", *QUICK, f"output={out}"))
    # The longest name written beside r.json: its temporary ".r.json.XXXXXXXX.tmp" (14
    # characters more than the name).
    assert message == (
        f"output={_short(str(out))}: the path is too long ({4453 + 14:,} bytes as a full "
        "path, with the files written beside it); this system allows at most 4,095 bytes"
    )
    assert _nothing_but_hydra(tmp_path)


def test_eval_output_name_leaving_no_room_for_its_lock_and_temporary_file(
    cli, tmp_path: Path
) -> None:
    """250 characters fit NAME_MAX, ``.<name>.XXXXXXXX.tmp`` (264) does not (with a
    suffix the temporary file is longer than the journal ``<stem>.episodes.jsonl``)."""
    out = tmp_path / ("n" * 245 + ".json")
    message = _one_error(cli("eval", *QUICK, f"output={out}"))
    assert message == (
        f"output={_short(str(out))}: the file name (250 characters) is too long for the "
        f"files written beside it: '.{'n' * 23}...{'n' * 6}.json.XXXXXXXX.tmp' is 264 bytes "
        "and names on its filesystem are at most 255; use a name of at most 241 bytes"
    )
    assert _nothing_but_hydra(tmp_path)


def test_eval_output_name_leaving_no_room_for_its_journal(cli, tmp_path: Path) -> None:
    """Without a suffix, the journal ``<name>.episodes.jsonl`` is the longest file
    written beside the output: 245 characters fit the temporary file, not the journal."""
    out = tmp_path / ("n" * 245)
    message = _one_error(cli("eval", *QUICK, f"output={out}"))
    assert message.endswith(
        "'nnnnnnnnnnnnnnnnnnnnnnnn...nnnnnnnnn.episodes.jsonl' is 260 bytes and names on "
        "its filesystem are at most 255; use a name of at most 240 bytes"
    )
    assert _nothing_but_hydra(tmp_path)


def test_the_longest_output_name_accepted_is_written(tmp_path: Path) -> None:
    out = tmp_path / ("n" * 241)
    with claim_file(out):
        atomic_write(out, lambda fh: fh.write(b"{}"))
    assert sorted(p.name for p in tmp_path.iterdir()) == [out.name]  # no lock file left
    with pytest.raises(ConfigError, match="use a name of at most 241 bytes"):
        runs.check_writable_file(tmp_path / ("n" * 242))


def test_a_name_longer_than_the_filesystem_allows(tmp_path: Path) -> None:
    out = tmp_path / ("n" * 256)
    with pytest.raises(ConfigError) as info:
        runs.check_writable_file(out)
    assert str(info.value) == (
        f"output={_short(str(out))}: the file name is 256 characters; names on its "
        "filesystem are at most 255 bytes"
    )


def test_non_ascii_names_are_measured_in_bytes(tmp_path: Path) -> None:
    out = tmp_path / ("é" * 130) / "r.json"  # 130 characters, 260 bytes in UTF-8
    with pytest.raises(ConfigError, match=r"the folder name '(é){24}\.\.\.(é){24}' is 260 bytes"):
        runs.check_writable_file(out)


def test_train_output_dir_with_a_too_long_name(cli, tmp_path: Path) -> None:
    folder = tmp_path / ("d" * 300)
    message = _one_error(cli("train", *TRAIN, f"output_dir={folder}"))
    assert message == (
        f"output_dir={_short(str(folder))}: the folder name '{'d' * 24}...{'d' * 24}' is "
        "300 characters; names on its filesystem are at most 255 bytes"
    )
    assert _nothing_but_hydra(tmp_path)


def test_train_output_dir_leaving_no_room_for_the_run_inside(cli, tmp_path: Path) -> None:
    """4,000 characters fit PATH_MAX, but not with the run's deepest files inside."""
    folder = _long_path(tmp_path, 4000)
    message = _one_error(cli("train", *TRAIN, f"output_dir={folder}"))
    assert message == (
        f"output_dir={_short(str(folder))}: the path is too long ({4000 + runs.RUN_PATH_ROOM:,} "
        "bytes as a full path, with the files written inside it); this system allows at "
        "most 4,095 bytes"
    )
    assert _nothing_but_hydra(tmp_path)


def test_a_run_folder_leaves_room_for_the_deepest_file_a_training_writes(tmp_path: Path) -> None:
    deepest = "logs/wandb/offline-run-20260101_000000-abcdefgh/logs/debug-internal.log"
    folder = check_writable_dir(_long_path(tmp_path, 4095 - runs.RUN_PATH_ROOM))
    (folder / deepest).parent.mkdir(parents=True)
    (folder / deepest).write_text("0,1\n")  # fits: the room is larger than it needs
    assert len(deepest) < runs.RUN_PATH_ROOM


def test_a_too_long_path_fails_its_job_not_the_sweep(cli, tmp_path: Path) -> None:
    long, ok = tmp_path / ("a" * 300) / "r.json", tmp_path / "ok" / "r.json"
    result = cli("eval", "--multirun", *QUICK, f"output={long},{ok}")
    assert result.code == 2
    assert "Traceback" not in result.err
    lines = result.err.strip().splitlines()
    assert lines[-1].startswith("error: 1 of 2 jobs failed")
    failed = next(tmp_path.glob("multirun/eval/*/*/0/FAILED")).read_text()
    expected = (
        f"output={_short(str(long))}: the folder name '{'a' * 24}...{'a' * 24}' is 300 "
        "characters; names on its filesystem are at most 255 bytes"
    )
    # The job is named by its overrides, the sweep's value of output= among them.
    assert re.fullmatch(
        rf"job 0 \(.* output={re.escape(str(long))}\): {re.escape(expected)}\n", failed
    )
    assert lines[0] == f"error: {failed.strip()}"
    assert ok.is_file()
    assert not list(tmp_path.glob("multirun/eval/*/*/1/FAILED"))


# --------------------------------------------------------------------------- free space
def _free(monkeypatch: pytest.MonkeyPatch, free: int) -> None:
    """The filesystem reports ``free`` bytes free (of 100 GiB)."""
    total = 100 * 2**30
    usage = shutil._ntuple_diskusage(total, total - free, free)  # type: ignore[attr-defined]
    monkeypatch.setattr(runs.shutil, "disk_usage", lambda path: usage)


def test_eval_refuses_a_nearly_full_filesystem(cli, tmp_path: Path, monkeypatch) -> None:
    _free(monkeypatch, int(1.2 * 2**20))
    out = tmp_path / "res" / "r.json"
    message = _one_error(cli("eval", *QUICK, f"output={out}"))
    assert message == (
        f"output={out}: only 1.2 MiB free on its filesystem; a run needs at least 32 MiB"
    )
    assert _nothing_but_hydra(tmp_path)


def test_train_refuses_a_nearly_full_filesystem(cli, tmp_path: Path, monkeypatch) -> None:
    _free(monkeypatch, 0)
    folder = tmp_path / "run"
    message = _one_error(cli("train", *TRAIN, f"output_dir={folder}"))
    assert message == (
        f"output_dir={folder}: only 0 MiB free on its filesystem; a run needs at least 32 MiB"
    )
    assert not folder.exists()


def test_a_caller_can_need_more_space(tmp_path: Path, monkeypatch) -> None:
    _free(monkeypatch, MIN_FREE_BYTES)
    with claim_folder(tmp_path / "a") as folder:  # exactly the minimum: enough
        assert (folder / LOCK_NAME).is_file()
    with pytest.raises(ConfigError) as info, claim_folder(tmp_path / "b", need=2**30):
        pass
    assert str(info.value) == (
        f"output_dir={tmp_path / 'b'}: only 32 MiB free on its filesystem; a run needs at "
        "least 1024 MiB"
    )


# --------------------------------------------------------------------------- writability
@pytest.mark.skipif(os.name != "posix" or os.geteuid() == 0, reason="root writes anywhere")
@pytest.mark.parametrize(("app", "key", "args"), [("eval", "output", QUICK),
                                                  ("train", "output_dir", TRAIN)])  # fmt: skip
def test_a_read_only_folder_is_named(cli, tmp_path: Path, app: str, key: str, args) -> None:
    folder = tmp_path / "ro"
    folder.mkdir()
    folder.chmod(0o555)
    target = folder / "r.json" if key == "output" else folder
    message = _one_error(cli(app, *args, f"{key}={target}"))
    assert message == f"{key}={target} cannot be written: Permission denied ({folder})"


def test_a_folder_refusing_new_files_is_named(tmp_path: Path, monkeypatch) -> None:
    """What a read-only folder gives a user who is not root (root writes anywhere)."""

    def refused(*args: object, dir: str, **kwargs: object) -> None:
        raise PermissionError(errno.EACCES, "Permission denied", dir)

    monkeypatch.setattr(runs.tempfile, "mkstemp", refused)
    with pytest.raises(ConfigError) as info, claim_folder(tmp_path / "run"):
        pass
    assert str(info.value) == (
        f"output_dir={tmp_path / 'run'} cannot be written: Permission denied ({tmp_path / 'run'})"
    )


# --------------------------------------------------------------------------- full disks
def _lock_open_fails(monkeypatch: pytest.MonkeyPatch, code: int) -> None:
    def fail(path: Path, mode: str) -> None:
        raise OSError(code, os.strerror(code), str(path))

    monkeypatch.setattr(runs, "open", fail, raising=False)


def test_a_full_disk_at_the_lock_is_one_line(cli, tmp_path: Path, monkeypatch) -> None:
    _lock_open_fails(monkeypatch, errno.ENOSPC)
    folder = tmp_path / "run"
    message = _one_error(cli("train", *TRAIN, f"output_dir={folder}"))
    assert message == (
        f"no space left on the device writing {folder / LOCK_NAME} ({NOSPACE}); the run did "
        f"not start and output_dir={folder} was left as it was"
    )
    assert list(folder.iterdir()) == []


def test_another_failure_at_the_lock_is_one_line(tmp_path: Path, monkeypatch) -> None:
    _lock_open_fails(monkeypatch, errno.EROFS)
    out = tmp_path / "r.json"
    with pytest.raises(ConfigError) as info, claim_file(out):
        pass
    assert str(info.value) == (
        f"output={out} cannot be written: Read-only file system ({tmp_path / '.r.json.lock'})"
    )


class _FullAfterOpen:
    """The lock file opens, then writing the pid finds the disk full."""

    def __init__(self, real: Any) -> None:
        self.real = real

    def __getattr__(self, name: str) -> Any:
        return getattr(self.real, name)

    def __enter__(self) -> _FullAfterOpen:
        return self

    def __exit__(self, *exc: object) -> None:
        self.real.close()

    def flush(self) -> None:
        raise OSError(errno.ENOSPC, NOSPACE)


def test_a_full_disk_writing_the_pid_is_one_line(tmp_path: Path, monkeypatch) -> None:
    def opened(path: Path, mode: str) -> _FullAfterOpen:
        return _FullAfterOpen(open(path, mode))

    monkeypatch.setattr(runs, "open", opened, raising=False)
    out = tmp_path / "r.json"
    with pytest.raises(DiskFullError) as info, claim_file(out):
        pass
    assert str(info.value) == (
        f"no space left on the device writing {tmp_path / '.r.json.lock'} ({NOSPACE}); the "
        f"run did not start and output={out} was left as it was"
    )


def test_an_error_of_the_run_is_not_renamed(tmp_path: Path) -> None:
    """The lock's guard covers the lock only: a full disk inside the run passes as it is."""
    with pytest.raises(OSError, match=NOSPACE) as info, claim_folder(tmp_path / "run"):
        raise OSError(errno.ENOSPC, NOSPACE, "elsewhere")
    assert type(info.value) is OSError


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="needs /dev/full")
def test_a_full_disk_in_atomic_write_keeps_the_previous_file(tmp_path: Path) -> None:
    """The write goes to /dev/full, where the kernel itself answers ENOSPC."""
    path = atomic_write(tmp_path / "results.json", lambda fh: fh.write(b'{"old": 1}'))
    full = os.open("/dev/full", os.O_WRONLY)

    def write(fh: Any) -> None:
        os.dup2(full, fh.fileno())
        fh.write(b"x" * (1 << 16))

    try:
        with pytest.raises(DiskFullError) as info:
            atomic_write(path, write)
    finally:
        os.close(full)
    assert str(info.value) == (
        f"no space left on the device writing {path} ({NOSPACE}); the previous results.json is kept"
    )
    assert path.read_bytes() == b'{"old": 1}'
    assert [p.name for p in tmp_path.iterdir()] == ["results.json"]


def _checkpoint(frames: int) -> dict[str, Any]:
    actor, critic = build_networks({})
    return {"model": {"actor": actor.state_dict(), "critic": critic.state_dict()},
            "model_config": {}, "frames": frames}  # fmt: skip


def _fsync_full(monkeypatch: pytest.MonkeyPatch) -> None:
    def full(fd: int) -> None:
        raise OSError(errno.ENOSPC, NOSPACE)

    monkeypatch.setattr(os, "fsync", full)


def test_a_full_disk_saving_a_checkpoint_keeps_the_previous_one(tmp_path: Path, monkeypatch):
    last = save_checkpoint(tmp_path / "last.pt", _checkpoint(512))
    _fsync_full(monkeypatch)
    with pytest.raises(DiskFullError) as info:
        save_checkpoint(last, _checkpoint(1024))
    monkeypatch.undo()
    assert str(info.value) == (
        f"no space left on the device writing {last} ({NOSPACE}); the previous last.pt is kept"
    )
    assert load_checkpoint(last)["frames"] == 512
    assert [p.name for p in tmp_path.iterdir()] == ["last.pt"]


def test_a_full_disk_at_the_first_write_leaves_nothing(tmp_path: Path, monkeypatch) -> None:
    _fsync_full(monkeypatch)
    with pytest.raises(DiskFullError, match=r"\); no best\.pt was written$"):
        save_checkpoint(tmp_path / "best.pt", _checkpoint(0))
    assert list(tmp_path.iterdir()) == []


@pytest.mark.skipif(sys.platform != "linux", reason="reads /proc/self/fd")
def test_a_full_disk_writing_the_results_is_one_line(cli, tmp_path: Path, monkeypatch) -> None:
    out = tmp_path / "r.json"
    assert cli("eval", *QUICK, f"output={out}").code == 0
    before = out.read_bytes()
    real = os.fsync

    def full_for_results(fd: int) -> None:
        if os.readlink(f"/proc/self/fd/{fd}").startswith(str(tmp_path / ".r.json.")):
            raise OSError(errno.ENOSPC, NOSPACE)
        real(fd)

    monkeypatch.setattr(os, "fsync", full_for_results)
    message = _one_error(cli("eval", *QUICK[:-1], "seeds=[1]", f"output={out}"))
    assert message == (
        f"no space left on the device writing {out} ({NOSPACE}); the previous r.json is kept"
    )
    assert out.read_bytes() == before
    assert not list(tmp_path.glob(".r.json.*.tmp"))
