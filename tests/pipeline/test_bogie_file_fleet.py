"""A fleet whose base tri-axle is a bogie file (issue 31 item 6) through the pipeline's own path: sample, simulate
(chunked, Parquet), read back verified."""

import copy
from pathlib import Path

import numpy as np

from pipeline.config import load_params, parse_config
from pipeline.sample import sample_studies
from pipeline.simulate import simulate_samples, study_protocols
from pipeline.survey import read_runs

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = "bogies/example_triaxle.yaml"


def weighed(tmp_path, triaxle):
    raw = copy.deepcopy(load_params(ROOT / "params.yaml"))
    raw["fleet"]["n_bogies"] = 8
    raw["fleet"]["presets"]["triaxle"] = triaxle
    raw["ablation"]["n_bogies"] = 1
    raw["sensitivity"]["base_size"] = 4
    raw["protocol"]["run"] = ["static"]
    raw["sensitivity"]["protocol"] = "static"
    raw["protocol"]["static"]["dt_s"] = 0.002
    raw["execution"].update({"backend": "loky", "n_jobs": 2, "chunk_size": 4, "dask_scheduler": None})
    config = parse_config(raw)
    fleet = sample_studies(config)["fleet"]
    out = tmp_path / triaxle.replace("/", "_")
    simulate_samples({"fleet": fleet}, {"fleet": study_protocols(config, "fleet")}, config.execution, out,
                     lambda line: None)  # fmt: skip
    return read_runs(out, "fleet").sort_values("sample_id").reset_index(drop=True)  # every part verified


def test_a_fleet_on_a_bogie_file_is_weighed_written_and_read_back(tmp_path, monkeypatch):
    monkeypatch.chdir(ROOT)  # a bogie file's path is relative to the project root, where the stages run
    runs = weighed(tmp_path, EXAMPLE)
    preset = weighed(tmp_path, "triaxle_stage1")
    tri = runs["group"] == "triaxle"
    assert len(runs) == 8 and (runs["status"] == "ok").all() and tri.any() and (~tri).any()
    assert set(runs.loc[tri, "preset"].astype(str)) == {EXAMPLE}
    assert set(runs.loc[~tri, "preset"].astype(str)) == {"tandem_trrl"}
    loads = ["axle_load_1", "axle_load_2", "axle_load_3"]
    np.testing.assert_allclose(runs[loads].sum(axis=1), runs["group_load"], rtol=1e-12)
    # the same samples on the preset tri-axle: the tandems read the same bits, the tri-axles read the file's geometry
    assert runs.loc[~tri, loads].equals(preset.loc[~tri, loads])
    assert not np.allclose(runs.loc[tri, loads].to_numpy(float), preset.loc[tri, loads].to_numpy(float), rtol=1e-3)
