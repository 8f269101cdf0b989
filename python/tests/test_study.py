"""pcr.study: study definitions, trials, a real 2-worker LocalCluster, stop and resume, failed
trials as rows, the plots and the pcr-study command."""
import json
import math
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

import pcr

study = pytest.importorskip("pcr.study", reason="the [study] extra is not installed")
pd = pytest.importorskip("pandas")


def _tour(q):
    """The rows of q along a greedy nearest-neighbour tour from the one nearest home, written
    here again as the reference the trial's order (the library's visiting_order) is held to."""
    left = list(range(len(q)))
    order = [left.pop(int(np.argmin(np.einsum("ij,ij->i", q, q))))] if left else []
    while left:
        d = q[left] - q[order[-1]]
        order.append(left.pop(int(np.argmin(np.einsum("ij,ij->i", d, d)))))
    return q[order]

# A small study for the cluster tests: 2 levels x 10 trials, few configurations and cycles.
SMALL = """
[study]
name = "small"
seed = 7
trials = 10

[factors]
calibration_count = 40
validation_count = 12
repeat = 3

[levels]
mount_tolerance = [80e-6, 320e-6]
"""
TIMES = ["time_s"] + [c for c in study.outcome_columns([]) if c.startswith("time.")]


def _command(*args):
    return [sys.executable, "-m", "pcr.study", *args]


def _without_times(table):
    return table.drop(columns=TIMES).reset_index(drop=True)


# ---- definitions ---------------------------------------------------------------------------

def test_builtin_studies_load_and_list_their_trials():
    assert study.builtin_studies() == ["configurations", "design-spatial", "tolerance",
                                       "tolerance-spatial", "unmodelled"]
    s = study.Study.load("tolerance")
    assert s.levels == {"mount_tolerance": [40e-6, 160e-6, 640e-6]} and s.trials == 50
    assert s.factors["calibration_count"] == 99 and s.factors["validation_count"] == 56
    trials = s.trial_list()
    assert len(trials) == 150
    # Trial i: replicate i // 3 of level i % 3; a replicate's seed is shared by the levels.
    assert [t.factors["mount_tolerance"] for t in trials[:4]] == [40e-6, 160e-6, 640e-6, 40e-6]
    assert [t.replicate for t in trials[:4]] == [0, 0, 0, 1]
    assert trials[0].seed == trials[1].seed == trials[2].seed != trials[3].seed
    assert len({t.seed for t in trials}) == 50 and all(0 <= t.seed < 2**63 for t in trials)
    # More trials extend the list; the first ones stay.
    assert s.replace(trials=60).trial_list()[:150] == trials


@pytest.mark.parametrize("text, message", [
    ("[levels]\nmount_tolerence = [1e-6]", "unknown factor 'mount_tolerence'"),
    ("[levels]\nmount_tolerance = [1e-6, 'x']", "levels.mount_tolerance[1]"),
    ("[levels]\nmount_tolerance = []", "expected a non-empty list"),
    ("[levels]\nmount_tolerance = [1e-6, 1e-6]", "appears twice"),
    ("[factors]\ncalibration_count = 9.5", "calibration_count = 9.5: expected a whole number"),
    ("[factors]\nnoise_position = -1e-9", "noise_position = -1e-09: expected a finite value >= 0"),
    ("[factors]\nrepeat = 0", "repeat = 0: expected at least 1"),
    ("[factors]\nrobot = 3", "robot = 3: expected a string"),
    ("[levels]\ndesign = ['poisson-disc', 'd-optimal', 'random']",
     "design = 'random': expected one of 'poisson-disc', 'd-optimal'"),
    ("[study]\ntrials = 0", "study.trials = 0"),
    ("[study]\nseeds = 3", "study.seeds: unknown field"),
    ("[trials]\nx = 1", "unknown table [trials]"),
    ("[factors]\nrepeat = 3\n[levels]\nrepeat = [2, 3]", "both a fixed factor and varied"),
    ("[study\n", "my.toml"),
])
def test_bad_study_files_are_refused_naming_the_field(tmp_path, text, message):
    path = tmp_path / "my.toml"
    path.write_text(text)
    with pytest.raises(ValueError, match="my.toml") as e:
        study.Study.load(path)
    assert message in str(e.value)
    r = subprocess.run(_command("run", str(path), "--output", str(tmp_path / "out")),
                       capture_output=True, text=True)
    assert r.returncode == 2 and message in r.stderr and "Traceback" not in r.stderr
    assert not (tmp_path / "out").exists()


def test_a_missing_study_names_the_built_in_ones(tmp_path):
    with pytest.raises(FileNotFoundError, match="tolerance"):
        study.Study.load(tmp_path / "nothing.toml")


# ---- one trial -----------------------------------------------------------------------------

FAST = dict(calibration_count=40, validation_count=12, repeat=3)


def test_a_trial_is_reproduced_from_its_factors_and_seed():
    a = study.run_trial(FAST, seed=11)
    b = study.run_trial(FAST, seed=11)
    c = study.run_trial(FAST, seed=12)
    assert a["failure"] is None, a["failure"]
    values = {k: v for k, v in a.items() if k not in TIMES and k != "failure"}
    assert all(math.isfinite(v) for v in values.values())
    assert values == {k: b[k] for k in values}
    assert c["table3.identified_model_validation_set.e_p_m.mean"] != \
        a["table3.identified_model_validation_set.e_p_m.mean"]
    # The method works: calibration brings the validation error from the nominal model's
    # (hundreds of um with the paper's tolerances) to near the camera noise (9 nm).
    nominal = a["table3.nominal_model_validation_set.e_p_m.mean"]
    identified = a["table3.identified_model_validation_set.e_p_m.mean"]
    assert identified < 1e-6 < nominal
    assert a["configurations.calibration"] == 40 and a["configurations.validation"] == 12


def test_trial_outcomes_are_those_of_the_json_report():
    """The pipeline by hand, through the public API, gives the trial's numbers."""
    seed = 5
    row = study.run_trial(FAST, seed)
    assert row["failure"] is None, row["failure"]
    truth_seed, _, sampling_seed, camera_seed = (
        int(s) for s in np.random.SeedSequence(seed).generate_state(4, dtype=np.uint64))
    design = pcr.Robot.default()
    truth = pcr.VirtualRobot(design, seed=truth_seed).truth
    assert row["parameters.l[1].error"] != 0
    sets = pcr.sample_configurations(design, count=40, validation_count=12, seed=sampling_seed)
    exact = truth.copy()
    exact.uncertainty = None
    robot = pcr.VirtualRobot(exact, seed=camera_seed)
    q, v = (_tour(sets[name]) for name in ("calibration", "validation"))  # as measured
    measured_q = robot.measure_dataset(q)["measured"]
    measured_v = robot.measure_dataset(v)["measured"]
    identified, result = pcr.calibrate(design, q, measured_q, drop_unreachable=True)
    table = pcr.calibration_table(result, q, measured_q, v, measured_v)
    report = result.to_dict(table)["table3"]
    for s in ("nominal_model_validation_set", "identified_model_validation_set"):
        for quantity in ("e_p_m", "e_theta_rad"):
            assert row[f"table3.{s}.{quantity}.mean"] == pytest.approx(
                report[s][quantity]["mean"], rel=1e-6)


def test_failed_trials_are_rows_with_their_reason(monkeypatch):
    # Half a newton on the platform: no configuration of the nominal model is an equilibrium
    # within the strokes on the true robot.
    row = study.run_trial(dict(FAST, load_force_x=0.5), seed=1)
    assert row["failure"].startswith("measurement: RuntimeError: none of the 40 calibration "
                                     "configurations is measured"), row["failure"]
    assert math.isnan(row["table3.identified_model_validation_set.e_p_m.mean"])
    assert row["time.sampling_s"] > 0 and row["time_s"] > 0
    # Trial 5 of the tolerance study (mounts +-640 um) once failed in the calibration (a stage's
    # start where an FK failed, Ceres: FAILURE); its equilibria are now continued in the
    # parameters, and it reaches the floor.
    trial = study.Study.load("tolerance").trial_list()[5]
    row = study.run_trial(trial.factors, trial.seed)
    assert row["failure"] is None
    assert row["table3.identified_model_validation_set.e_p_m.mean"] < 0.1e-6
    # A calibration that fails is a row naming the stage (an error raised as it begins, through
    # the library's run_method) and its reason.
    run_method = pcr.run_method

    def failing(*args, on_stage, **kwargs):
        def enter(stage):
            on_stage(stage)
            if stage == "calibration":
                raise RuntimeError("stage 'all' did not converge")
        return run_method(*args, on_stage=enter, **kwargs)

    monkeypatch.setattr(pcr, "run_method", failing)
    row = study.run_trial(dict(FAST), seed=1)
    assert row["failure"] == "calibration: RuntimeError: stage 'all' did not converge"
    assert row["time.measurement_s"] > 0
    assert math.isnan(row["table3.identified_model_validation_set.e_p_m.mean"])
    monkeypatch.undo()
    row = study.run_trial(dict(FAST, robot="/nonexistent/robot.json"), seed=1)
    assert row["failure"].startswith("design: ") and "/nonexistent/robot.json" in row["failure"]


# ---- a study on a real LocalCluster --------------------------------------------------------

@pytest.fixture(scope="module")
def small(tmp_path_factory):
    """The small study, uninterrupted, on 2 worker processes: (definition, table, directory)."""
    directory = tmp_path_factory.mktemp("study") / "uninterrupted"
    definition = study.Study.from_toml(SMALL, "small.toml")
    table = study.run(definition, directory, workers=2, progress=False)
    return definition, table, directory


def test_a_study_runs_on_two_workers_into_parquet(small):
    definition, table, directory = small
    assert len(table) == 20 and list(table["trial"]) == list(range(20))
    assert table["failure"].isna().all(), table["failure"].dropna().tolist()
    assert sorted(table["mount_tolerance"].unique()) == [80e-6, 320e-6]
    assert (table["calibration_count"] == 40).all() and (table["repeat"] == 3).all()
    assert (table["seed"] == [definition.trial_seed(i // 2) for i in range(20)]).all()
    # Any Parquet reader sees the same rows (the manifest and temporary files are skipped).
    plain = pd.read_parquet(directory).sort_values("trial").reset_index(drop=True)
    pd.testing.assert_frame_equal(plain, table, check_dtype=False)
    # A trial reruns alone from its row to the same outcomes.
    row = table.iloc[13]
    again = study.run_trial({k: row[k] for k in ("mount_tolerance", *definition.factors)},
                            int(row["seed"]))
    assert again["accuracy.circle.identified.ap_p.mean"] == \
        row["accuracy.circle.identified.ap_p.mean"]


def test_a_study_runs_on_a_scheduler_and_workers_started_as_commands(small, tmp_path):
    """As on a cluster without Slurm: `dask scheduler` and `dask worker ADDRESS` started as their
    own processes, and `pcr-study run --scheduler tcp://...` giving the LocalCluster's table."""
    definition, table, _ = small
    path = tmp_path / "small.toml"
    path.write_text(SMALL)
    address_file = tmp_path / "scheduler.json"
    log = open(tmp_path / "dask.log", "w")
    scheduler = subprocess.Popen(
        [sys.executable, "-m", "distributed.cli.dask_scheduler", "--host", "127.0.0.1",
         "--port", "0", "--dashboard-address", ":0", "--scheduler-file", str(address_file)],
        stdout=log, stderr=subprocess.STDOUT)
    workers = None
    try:
        deadline = time.monotonic() + 60
        while not address_file.exists() and time.monotonic() < deadline:
            assert scheduler.poll() is None, (tmp_path / "dask.log").read_text()
            time.sleep(0.1)
        address = json.loads(address_file.read_text())["address"]
        assert address.startswith("tcp://127.0.0.1:")
        workers = subprocess.Popen(
            [sys.executable, "-m", "distributed.cli.dask_worker", address, "--nworkers", "2",
             "--nthreads", "1", "--no-dashboard", "--local-directory", str(tmp_path)],
            stdout=log, stderr=subprocess.STDOUT)
        out = tmp_path / "remote"
        r = subprocess.run(_command("run", str(path), "--output", str(out), "--scheduler",
                                    address, "--quiet"),
                           capture_output=True, text=True, timeout=600)
        assert r.returncode == 0, r.stderr + (tmp_path / "dask.log").read_text()
        remote = study.read_results(out)
        pd.testing.assert_frame_equal(_without_times(remote), _without_times(table))
    finally:
        for process in (workers, scheduler):
            if process is not None:
                process.terminate()
                try:
                    process.wait(timeout=30)
                except subprocess.TimeoutExpired:
                    process.kill()
        log.close()


def test_a_stopped_study_resumes_to_the_uninterrupted_table(small, tmp_path):
    definition, table, _ = small
    path = tmp_path / "small.toml"
    path.write_text(SMALL)
    out = tmp_path / "stopped"
    args = _command("run", str(path), "--output", str(out), "--workers", "2", "--batch-size",
                    "1", "--flush-seconds", "0")
    process = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and process.poll() is None and not any(
            p.name.startswith("part-") for p in out.glob("*.parquet")):
        time.sleep(0.05)
    process.send_signal(signal.SIGINT)
    _, err = process.communicate(timeout=120)
    assert process.returncode == 130, err
    assert "resumes the study" in err
    partial = study.read_results(out)
    assert 0 < len(partial) < 20, "stopped too late to test a resume"
    r = subprocess.run(args, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    resumed = study.read_results(out)
    pd.testing.assert_frame_equal(_without_times(resumed), _without_times(table))
    # The trials written before the stop were not run again.
    first = partial.set_index("trial")["time_s"]
    assert (resumed.set_index("trial").loc[first.index, "time_s"] == first).all()


def test_failing_trials_do_not_stop_a_study(tmp_path):
    failing = study.Study.from_toml(
        "[study]\ntrials = 2\n[factors]\ncalibration_count = 40\nvalidation_count = 12\n"
        "repeat = 3\n[levels]\nload_force_x = [0.0, 0.5]\n", "failing.toml")
    table = study.run(failing, tmp_path / "out", workers=2, progress=False)
    assert len(table) == 4
    failed = table[table["load_force_x"] == 0.5]
    assert failed["failure"].str.startswith("measurement: RuntimeError: none of the").all()
    assert failed["table3.identified_model_validation_set.e_p_m.mean"].isna().all()
    assert table.loc[table["load_force_x"] == 0.0, "failure"].isna().all()


def test_robot_files_are_named_relative_to_the_study_and_held_to_their_content(tmp_path,
                                                                              monkeypatch):
    design = pcr.Robot.default().with_limb(1, l=0.0302)
    design.save(tmp_path / "mine.json")
    (tmp_path / "mine.toml").write_text(
        "[study]\ntrials = 1\n[factors]\nrobot = 'mine.json'\ncalibration_count = 40\n"
        "validation_count = 12\nrepeat = 3\n")
    monkeypatch.chdir(tmp_path.parent)  # not where the study is
    s = study.Study.load(tmp_path / "mine.toml")
    assert s.factors["robot"] == str(tmp_path / "mine.json")
    table = study.run(s, tmp_path / "out", workers=1, progress=False)
    assert table["failure"].isna().all() and table["robot"][0] == str(tmp_path / "mine.json")
    design.with_limb(1, l=0.0303).save(tmp_path / "mine.json")
    with pytest.raises(ValueError, match="robot files changed"):
        study.run(s, tmp_path / "out", workers=1, progress=False)


def test_results_of_another_study_are_not_mixed(small, tmp_path):
    _, _, directory = small
    other = study.Study.from_toml(SMALL.replace("seed = 7", "seed = 8"), "other.toml")
    with pytest.raises(ValueError, match="another study"):
        study.run(other, directory, workers=1, progress=False)
    foreign = tmp_path / "foreign"
    foreign.mkdir()
    (foreign / "notes.txt").write_text("mine")
    r = subprocess.run(_command("run", "tolerance", "--output", str(foreign)),
                       capture_output=True, text=True)
    assert r.returncode == 2 and "holds no study" in r.stderr
    assert (foreign / "notes.txt").read_text() == "mine" and len(list(foreign.iterdir())) == 1
    a_file = tmp_path / "a-file"
    a_file.write_text("x")
    r = subprocess.run(_command("run", "tolerance", "--output", str(a_file)),
                       capture_output=True, text=True)
    assert r.returncode == 2 and "not a directory" in r.stderr and a_file.read_text() == "x"


def test_the_plots_render(small, tmp_path):
    _, table, directory = small
    out = tmp_path / "plots"
    r = subprocess.run(_command("plot", str(directory), "--output", str(out)),
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    for name in ("factors.png", "sensitivity.png"):
        data = (out / name).read_bytes()
        assert data.startswith(b"\x89PNG") and len(data) > 10000
    summary = pd.read_csv(out / "summary.csv")
    assert set(summary["level"]) == {80e-6, 320e-6} and (summary["trials"] == 10).all()
    median = summary.query("outcome == 'table3.identified_model_validation_set.e_p_m.mean' and "
                           "level == 8e-5")["median"].item()
    assert median == pytest.approx(
        table.loc[table["mount_tolerance"] == 80e-6,
                  "table3.identified_model_validation_set.e_p_m.mean"].median())


def test_the_summary_gives_the_tables_headline(small):
    _, table, directory = small
    r = subprocess.run(_command("summary", str(directory)), capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert r.stdout.startswith("20 trials, 0 failed\n")
    column = table["table3.identified_model_validation_set.e_p_m.mean"]
    line = next(x for x in r.stdout.splitlines()
                if x.startswith("| identified_model_validation_set |"))
    cells = [c.strip() for c in line.strip("|").split("|")]
    assert cells[1] == "20"
    assert float(cells[2]) == pytest.approx(column.median() * 1e6, rel=1e-3)
    assert float(cells[3]) == pytest.approx(column.max() * 1e6, rel=1e-3)
    unmeasured = int(table["configurations.unreachable"].sum())
    assert f"did not measure (no stable equilibrium there): {unmeasured} in" in r.stdout


def test_a_study_without_finished_trials_is_not_plotted(tmp_path):
    definition = study.Study.from_toml(SMALL, "small.toml")
    study.run(definition, tmp_path / "out", trials=1, workers=1, progress=False)
    for part in (tmp_path / "out").glob("part-*.parquet"):
        part.unlink()
    r = subprocess.run(_command("plot", str(tmp_path / "out")), capture_output=True, text=True)
    assert r.returncode == 2 and "no finished trial to plot yet" in r.stderr
    assert not (tmp_path / "out" / "_plots").exists()


def test_sensitivity_ranks_the_factor_that_sets_the_outcome():
    rng = np.random.default_rng(3)
    a = rng.choice([1.0, 10.0, 100.0], 300)
    b = rng.choice([1.0, 2.0], 300)
    table = pd.DataFrame({"a": a, "b": b, "y": a * np.exp(rng.normal(0, 0.05, 300)),
                          "failure": [None] * 300})
    ranking = study.sensitivity(table, "y", ["b", "a"])
    assert list(ranking["factor"]) == ["a", "b"]
    assert ranking["eta_squared"][0] > 0.99 and ranking["eta_squared"][1] < 0.01


def test_the_command_lists_the_built_in_studies():
    r = subprocess.run(_command("list"), capture_output=True, text=True)
    assert r.returncode == 0 and "tolerance: " in r.stdout and "mount_tolerance" in r.stdout
    if os.environ.get("PCR_EXPECT_INSTALLED"):  # pip install put the console script there
        script = os.path.join(os.path.dirname(sys.executable), "pcr-study")
        r = subprocess.run([script, "list"], capture_output=True, text=True)
        assert r.returncode == 0 and "configurations: " in r.stdout


def test_the_plots_speak_in_words_and_units():
    from pcr.study._plot import factors_figure, outcome_label, sensitivity_figure

    assert outcome_label("table3.identified_model_validation_set.e_p_m.mean") == (
        "mean position error e_p, identified model, validation set", 1e6, "µm")
    assert outcome_label("accuracy.circle.nominal.ap_theta_abs.max") == (
        "max orientation accuracy |AP_θ| on the circle, nominal model", 1e6, "µrad")
    definition = study.Study.from_toml(SMALL, "small.toml")
    rng = np.random.default_rng(5)
    levels = np.repeat([80e-6, 320e-6], 10)
    table = pd.DataFrame({"mount_tolerance": levels, "failure": [None] * 19 + ["sampling: x"],
                          "parameters.A_x[0].error": rng.normal(0, 1e-6, 20)})
    outcomes = list(study._plot.DEFAULT_OUTCOMES)
    for o in outcomes:
        table[o] = levels * 1e-3 * np.exp(rng.normal(0, 0.1, 20))
    fig = factors_figure(table, definition, outcomes)
    axes = fig.axes
    assert len(axes) == len(outcomes)
    labels = [" ".join(ax.get_ylabel().split()) for ax in axes]
    assert labels[0] == "mean position error e_p, identified model, validation set (µm)"
    assert "(µrad)" in labels[2] and not any("." in label.split("(")[0] for label in labels)
    assert axes[0].get_xlabel().startswith("mount tolerance: half-width of the mount positions")
    assert [t.get_text() for t in axes[0].get_xticklabels()] == ["80 µm", "320 µm"]
    median = np.median(table.loc[table["mount_tolerance"] == 80e-6, outcomes[0]]) * 1e6
    assert any(np.allclose(line.get_ydata(), median) for line in axes[0].get_lines())  # in µm
    assert "robot the paper's (default)" in fig.texts[0].get_text()
    assert "failed trials: 0, 1" in axes[0].get_title()
    fig, _, _ = sensitivity_figure(table, definition, outcomes[0])
    assert "mean position error e_p, identified model" in fig.texts[0].get_text()
