"""``rtaw-study``: run a study and print its tables; optionally rewrite its docs section.

Examples::

    rtaw-study study=transfer workers=2
    rtaw-study study=table1_paper seeds=[0,1,2] output=runs/t1
    rtaw-study study=table1_paper output=runs/t1 resume=true   # after a kill
    rtaw-study study=table1_paper docs=docs reuse=true write=true workers=2   # docs/results.md

The tables go to stdout and are saved as ``<study>.txt`` beside ``<study>.json`` in the
run folder; progress lines go to stderr.
"""

from __future__ import annotations

from pathlib import Path

from hydra.core.hydra_config import HydraConfig
from omegaconf import DictConfig

from rtaw_marl.cli.common import exit_on_user_error, hydra_entry, typed
from rtaw_marl.errors import ConfigError
from rtaw_marl.evaluation.config import StudyConfig
from rtaw_marl.evaluation.studies import study as find_study
from rtaw_marl.evaluation.study import (
    StudyResult,
    load_result,
    replace_section,
    run_study,
    save_result,
)
from rtaw_marl.evaluation.transcript import Transcript, transcript_path
from rtaw_marl.utils.runs import claim_file


@exit_on_user_error
def run(cfg: DictConfig | StudyConfig) -> StudyResult:
    """Run ``cfg.study``; print its tables and write them where asked. Returns the result."""
    cfg = typed(cfg)
    study = find_study(cfg.study)
    seeds = list(study.default_seeds if cfg.seeds is None else cfg.seeds)
    docs = None if cfg.docs is None else Path(cfg.docs)
    stored = {name: _stored(docs, name, cfg.study) for name in study.pairs_with}
    if cfg.write and study.page is not None and not (docs / study.page).is_file():
        raise ConfigError(f"write=true: {docs / study.page} does not exist")
    output = Path(cfg.output or HydraConfig.get().runtime.output_dir)
    with claim_file(output / f"{study.name}.json") as path:
        reuse = load_result(docs / "data" / f"{study.name}.json") if cfg.reuse else None
        result = run_study(study, seeds, output, cfg.workers, cfg.resume, reuse, cfg.reuse_learned)
        save_result(path, result)
    body = study.render(result, stored)
    report = Transcript()
    report.print(body)
    report.print(f"results: {path}")
    if cfg.write:
        if study.store:
            save_result(docs / "data" / f"{study.name}.json", result)
        if study.page is not None:
            replace_section(docs / study.page, study.name, body)
            report.print(f"rewrote the {study.name} section of {docs / study.page}")
    report.save(transcript_path(path))
    return result


def _stored(docs: Path | None, name: str, study: str) -> StudyResult:
    """A stored result that ``study``'s tables pair with."""
    if docs is None:
        raise ConfigError(f"study={study} pairs with the stored {name} results: give docs=FOLDER")
    result = load_result(docs / "data" / f"{name}.json")
    if result is None:
        raise ConfigError(f"study={study} needs {docs}/data/{name}.json: run study={name} first")
    return result


main = hydra_entry("study", run)

if __name__ == "__main__":
    main()
