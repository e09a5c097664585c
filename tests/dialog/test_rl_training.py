"""teachbot train-questioner: a tiny masked-PPO run saves, reloads and plays a policy in regress, demo and teach."""

import json
import os

import pytest

pytest.importorskip("sb3_contrib", reason="the rl extra (pip install -e '.[rl]') installs sb3-contrib")

from dialog.cli import main  # noqa: E402
from dialog.rl.gym_env import QuestioningEnv  # noqa: E402
from dialog.rl.training import actor_policy  # noqa: E402
from dialog.transcripts.jsonl import read_session  # noqa: E402
from learning.rl.policy_file import load_policy  # noqa: E402

TINY = ["--turns", "8", "--budget", "8", "--change-every", "4"]


def test_the_numpy_actor_chooses_what_maskable_ppo_chooses():
    from sb3_contrib import MaskablePPO

    env = QuestioningEnv(turns=8, budget=8.0, change_every=4)
    model = MaskablePPO("MlpPolicy", env, seed=3, device="cpu", n_steps=64, batch_size=32)
    model.learn(64)  # weights away from their initial values
    policy = actor_policy(model, env.layout, {"test": True})
    obs, info = env.reset(seed=4)
    for _ in range(6):
        mask = info["action_mask"]
        theirs, _ = model.predict(obs, action_masks=mask, deterministic=True)
        assert policy.best_slot(obs, mask) == int(theirs)
        obs, _, _, _, info = env.step(int(theirs))


@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    folder = tmp_path_factory.mktemp("questioner")
    here = os.getcwd()
    os.chdir(folder)  # a folder that does not exist yet is created inside the current one (issue 23, case 1)
    try:
        assert main(["train-questioner", "--out", "new-folder/q.toml", "--steps", "256", "--envs", "1", "--seed",
                     "1", "--no-progress", *TINY]) == 0
    finally:
        os.chdir(here)
    return folder / "new-folder" / "q.toml"


def test_a_tiny_training_run_saves_a_policy_that_reloads(trained, capsys):
    policy = load_policy(trained)
    assert policy.layout.concepts == ("main dish", "snack", "fruit", "beverage") and policy.layout.max_objects == 12
    provenance = policy.provenance
    assert provenance["algorithm"].startswith("MaskablePPO") and provenance["steps"] >= 256
    assert provenance["env_data_seed"] == 100 and provenance["env_turns"] == 8 and len(provenance["commit"]) >= 7
    assert provenance["env_objects_per_scene"] == 12  # the task's own size when --objects is not given
    assert trained.with_suffix(".npz").is_file()


def test_regress_runs_the_policy_beside_the_suite_strategies(trained, tmp_path, capsys):
    results = tmp_path / "results"
    code = main(["regress", "--suite", "smoke", "--strategies", "active", f"rl:{trained}", "--seeds", "0",
                 "--datasets", "1", "--results", str(results), "--no-progress", "--json"])
    assert code == 0
    summary = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert summary["episodes"] == 2 and summary["passed"]
    transcript = results / "transcripts" / "static" / "rl-q-d0-s0.jsonl"
    header, records = read_session(transcript)
    assert header["strategy"] == f"rl:{trained}" and len(records) == 20
    assert header["policy"]["file"] == str(trained.resolve())
    assert any(r["action"]["kind"] != "none" for r in records)


def test_demo_and_teach_run_it_and_a_resume_checks_the_file(trained, tmp_path, capsys):
    demo = tmp_path / "demo.jsonl"
    assert main(["demo", "--strategy", f"rl:{trained}", "--turns", "2", "--transcript", str(demo), "--json"]) == 0
    assert json.loads(capsys.readouterr().out.strip().splitlines()[-1])["strategy"] == f"rl:{trained.resolve()}"
    teach = tmp_path / "teach.jsonl"
    assert main(["teach", "--teacher", "scripted", "--strategy", f"rl:{trained}", "--turns", "2",
                 "--transcript", str(teach), "--no-pictures"]) == 0
    trained.with_suffix(".npz").write_bytes(trained.with_suffix(".npz").read_bytes())  # same bytes: still fine
    lines = teach.read_text().splitlines()
    teach.write_text("\n".join(lines[:2]) + "\n")  # one turn recorded: resume the second
    assert main(["teach", "--resume", str(teach), "--no-pictures"]) == 0
    text = trained.read_text()
    trained.write_text(text + "# edited\n")
    try:
        teach.write_text("\n".join(lines[:2]) + "\n")
        assert main(["teach", "--resume", str(teach), "--no-pictures"]) == 2
        assert "changed since the session was recorded" in capsys.readouterr().err
    finally:
        trained.write_text(text)


def test_a_missing_policy_is_one_line(tmp_path, capsys):
    assert main(["demo", "--strategy", f"rl:{tmp_path / 'none.toml'}", "--turns", "1"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "no questioner policy file there" in err
    with pytest.raises(SystemExit) as exited:  # argparse's own exit, in the tool's voice
        main(["demo", "--strategy", "nonsense"])
    err = capsys.readouterr().err
    assert exited.value.code == 2 and "rl:FILE (a trained questioner policy .toml)" in err and err.count("\n") == 1


def test_a_bad_out_path_is_one_line_before_any_training(tmp_path, capsys):
    assert main(["train-questioner", "--out", str(tmp_path / "q.json")]) == 2
    assert "must end in .toml" in capsys.readouterr().err
    blocker = tmp_path / "file"
    blocker.write_text("")
    assert main(["train-questioner", "--out", str(blocker / "q.toml")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "Traceback" not in err and str(blocker) in err


def test_the_time_estimate_is_said_before_training_and_again_after_the_first_rollout():
    from dialog.rl.training import TrainingConfig, train

    lines: list[str] = []
    config = TrainingConfig(steps=256, envs=1, seed=2, n_steps=64, batch_size=32, epochs=1,
                            env={"turns": 8, "budget": 8, "change_every": 4})
    _, summary = train(config, progress=False, say=lines.append)
    before = [line for line in lines if line.startswith("this will take about")]
    again = [line for line in lines if line.startswith("after the first 64 steps")]
    assert len(before) == 1 and "timed on 2+ whole episodes" in before[0]
    assert len(again) == 1 and again[0].endswith("left"), lines
    assert summary["estimated_seconds"] > 0
