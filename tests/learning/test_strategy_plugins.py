"""``module.path:ClassName``: a user's strategy loaded from an importable module, everywhere a strategy is named."""

import json

import pytest

from dialog.cli import main
from dialog.experiments.kinds import get_kind
from dialog.experiments.suite import SuiteError, load_suite
from learning import Strategy, check_strategy
from learning.errors import DataFileError, SettingsError
from learning.strategies import STRATEGY_NAMES, check_strategy_name, file_label, is_external, make_strategy
from tests.dialog.test_regress import SUITE, write_suite

MYSTRATEGY = '''
from learning import Decision, LabelQuery, NoQuery, Strategy


class MyStrategy(Strategy):
    def choose(self, state, rng):
        if len(state.scene_X) and state.can_afford(LabelQuery(0)):
            return Decision(LabelQuery(int(rng.integers(len(state.scene_X)))), "Any object will do.")
        return Decision(NoQuery(), "Nothing to ask.")


class Named(MyStrategy):
    name = "mine"


class DuckTyped:
    def choose(self, state, rng):
        return Decision(NoQuery(), "I never ask.")


class NeedsArguments(MyStrategy):
    def __init__(self, level):
        self.level = level


class Broken(Strategy):
    def choose(self, state, rng):
        return Decision(LabelQuery(999), "Object 999, please.")


class BreaksInTheKitchen(Strategy):
    """Keeps the contract on check_strategy's small scenes, asks one past the last object of a kitchen scene."""

    def choose(self, state, rng):
        if len(state.scene_X) > 6 and state.can_afford(LabelQuery(0)):
            return Decision(LabelQuery(len(state.scene_X)), "The one after the last.")
        return Decision(NoQuery(), "Nothing to ask.")


NOT_A_CLASS = 3
'''


@pytest.fixture
def mypkg(tmp_path, monkeypatch):
    """A package ``mypkg`` on sys.path, as a user's own would be on PYTHONPATH."""
    package = tmp_path / "plugins" / "mypkg"
    package.mkdir(parents=True)
    (package / "__init__.py").write_text("")
    (package / "mystrategy.py").write_text(MYSTRATEGY)
    (package / "broken.py").write_text("raise RuntimeError('the module is broken')\n")
    monkeypatch.syspath_prepend(str(tmp_path / "plugins"))
    yield "mypkg.mystrategy"
    import sys

    for name in [m for m in sys.modules if m == "mypkg" or m.startswith("mypkg.")]:
        del sys.modules[name]


def test_a_user_class_loads_and_is_named_by_its_spec(mypkg):
    strategy = make_strategy(f"{mypkg}:MyStrategy")
    assert isinstance(strategy, Strategy) and strategy.name == "mypkg.mystrategy:MyStrategy"
    assert make_strategy(f"{mypkg}:Named").name == "mine"  # a name of its own is kept
    duck = make_strategy(f"{mypkg}:DuckTyped")  # not a Strategy subclass, but has choose(state, rng)
    assert duck.name == "mypkg.mystrategy:DuckTyped" and check_strategy(duck).states == 18
    assert make_strategy(f"{mypkg}:NeedsArguments", level=2).level == 2  # options go to the constructor
    assert check_strategy(strategy).name == "mypkg.mystrategy:MyStrategy"


@pytest.mark.parametrize("spec, words", [
    ("mypkg/mystrategy.py:MyStrategy", "not a file path; put the file's folder on PYTHONPATH"),
    ("mystrategy.py:MyStrategy", "not a file path"),
    ("mypkg.mystrategy:", "is not of the form module.path:ClassName"),
    ("my-pkg:MyStrategy", "is not of the form module.path:ClassName"),
    ("mypkg.nothere:MyStrategy", "can't import module 'mypkg.nothere' (ModuleNotFoundError"),
    ("mypkg.broken:MyStrategy", "can't import module 'mypkg.broken' (RuntimeError: the module is broken)"),
    ("mypkg.mystrategy:Missing", "module 'mypkg.mystrategy' has no 'Missing'"),
    ("mypkg.mystrategy:NOT_A_CLASS", "'NOT_A_CLASS' is not a strategy class (a subclass of learning.Strategy"),
    ("mypkg.mystrategy:Decision", "'Decision' is not a strategy class"),
    ("mypkg.mystrategy:NeedsArguments", "NeedsArguments() failed (TypeError"),
])
def test_a_bad_spec_is_one_message_naming_it_and_what_is_accepted(mypkg, spec, words):
    with pytest.raises(SettingsError) as refused:
        make_strategy(spec)
    message = str(refused.value)
    assert message.startswith(f"strategy '{spec}'") and words in message and "\n" not in message
    assert any(accepted in message for accepted in ("module.path:ClassName", "a subclass of learning.Strategy",
                                                    "must build with no arguments"))  # what is accepted


def test_names_and_file_labels(mypkg):
    assert is_external(f"{mypkg}:MyStrategy") and is_external("rl:x.toml") and not is_external("dt-task")
    assert file_label(f"{mypkg}:MyStrategy") == "mypkg.mystrategy.MyStrategy"  # no ':' in a file name
    assert file_label("rl:some/where/questioner.toml") == "rl-questioner" and file_label("active") == "active"
    assert check_strategy_name(f"{mypkg}:MyStrategy") == f"{mypkg}:MyStrategy"
    with pytest.raises(SettingsError, match="unknown strategy 'clever'; choose one of: passive, .*module.path:Cl"):
        check_strategy_name("clever")
    with pytest.raises(SettingsError, match="unknown strategy 'dt-tsk' \\(did you mean 'dt-task'\\?\\)"):
        make_strategy("dt-tsk")
    assert len(STRATEGY_NAMES) == 20  # nothing registered by loading a plugin


def test_a_suite_accepts_a_plugin_and_refuses_a_broken_one_before_running(mypkg, tmp_path):
    text = SUITE.replace('"active"]', f'"active", "{mypkg}:MyStrategy"]')
    suite = load_suite(write_suite(tmp_path, text), STRATEGY_NAMES)
    assert get_kind(suite.kind).load(suite).strategies[-1] == "mypkg.mystrategy:MyStrategy"
    broken = load_suite(write_suite(tmp_path, SUITE.replace('"active"]', '"active", "mypkg.broken:X"]')),
                        STRATEGY_NAMES)
    with pytest.raises(SuiteError, match="tiny.toml: strategy 'mypkg.broken:X': can't import module"):
        get_kind(broken.kind).load(broken)


def test_regress_runs_a_users_strategy_from_an_importable_module(mypkg, tmp_path, capsys):
    out = tmp_path / "out"
    code = main(["regress", "--suite", str(write_suite(tmp_path)), "--results", str(out), "--workers", "1",
                 "--strategies", "active", f"{mypkg}:MyStrategy", "--no-progress", "--json"])
    assert code == 0
    assert json.loads(capsys.readouterr().out.strip().splitlines()[-1])["episodes"] == 4
    assert "| mypkg.mystrategy:MyStrategy |" in (out / "report.md").read_text()
    assert (out / "transcripts" / "static" / "mypkg.mystrategy.MyStrategy-d0-s0.jsonl").is_file()
    assert (out / "episodes" / "static" / "mypkg.mystrategy.MyStrategy-d0-s0.csv").is_file()


def test_the_command_line_refuses_a_bad_spec_in_one_line(mypkg, capsys):
    with pytest.raises(SystemExit) as exited:
        main(["demo", "--strategy", "mypkg.mystrategy:Missing", "--turns", "1"])
    assert exited.value.code == 2
    err = capsys.readouterr().err.strip()
    assert "module 'mypkg.mystrategy' has no 'Missing'" in err and len(err.splitlines()) == 1


def test_a_study_file_takes_a_plugin_and_refuses_a_broken_one(mypkg, tmp_path):
    from dialog.study.studyfile import load_study
    from tests.dialog.study.test_studyfile import GOOD

    path = tmp_path / "study.toml"
    path.write_text(GOOD.replace('strategy = "passive"', f'strategy = "{mypkg}:MyStrategy"'))
    assert load_study(path).conditions[1].strategy == "mypkg.mystrategy:MyStrategy"
    path.write_text(GOOD.replace('strategy = "passive"', 'strategy = "mypkg/mystrategy.py:MyStrategy"'))
    with pytest.raises(DataFileError, match="study.toml \\[\\[conditions\\]\\] 2: strategy 'mypkg/mystrategy.py:"
                                            "MyStrategy': a strategy is loaded from an importable module, not a file"):
        load_study(path)


@pytest.mark.e2e
def test_a_teach_session_records_a_plugin_and_its_resume_checks_it_still_loads(tmp_path, capsys):
    spec = "learning.strategies.examples:EveryOtherTurn"
    path = tmp_path / "session.jsonl"
    assert main(["teach", "--teacher", "scripted", "--strategy", spec, "--turns", "2", "--budget", "5",
                 "--transcript", str(path), "--no-pictures"]) == 0
    lines = [json.loads(line) for line in path.read_text().splitlines()]
    assert lines[0]["session"]["strategy"] == spec and [r["action"]["kind"] for r in lines[1:]] == ["label", "none"]
    lines[0]["session"]["strategy"] = "learning.strategies.gone:EveryOtherTurn"
    path.write_text("".join(json.dumps(line) + "\n" for line in lines))
    capsys.readouterr()
    assert main(["teach", "--resume", str(path), "--no-pictures"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"teachbot teach: {path}: line 1: the session header's strategy can't be loaded now: "
                          "strategy 'learning.strategies.gone:EveryOtherTurn': can't import module") and \
        len(err.splitlines()) == 1


# -- a plug-in that returns an invalid action is refused, not mended into quiet turns (issue 42, case 1) --------
def test_a_plugin_that_breaks_the_contract_is_refused_when_loaded(mypkg):
    with pytest.raises(SettingsError) as refused:
        make_strategy(f"{mypkg}:Broken")
    message = str(refused.value)
    assert message.startswith("strategy 'mypkg.mystrategy:Broken' is refused (learning.check_strategy): a strategy "
                              "asks only affordable, admissible actions: on ") and "object 999" in message
    assert "\n" not in message


@pytest.mark.parametrize("command", [
    ["demo", "--turns", "2"],
    ["teach", "--teacher", "scripted", "--turns", "2", "--no-pictures"],
])
def test_demo_and_teach_refuse_a_broken_plugin_in_one_line_before_playing(mypkg, command, tmp_path, capsys):
    path = tmp_path / "t.jsonl"
    with pytest.raises(SystemExit) as exited:
        main([*command, "--strategy", f"{mypkg}:Broken", "--transcript", str(path)])
    assert exited.value.code == 2 and not path.exists()
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "strategy 'mypkg.mystrategy:Broken' is refused" in err, err


def test_regress_refuses_a_broken_plugin(mypkg, tmp_path, capsys):
    assert main(["regress", "--suite", str(write_suite(tmp_path)), "--results", str(tmp_path / "out"), "--workers",
                 "1", "--strategies", f"{mypkg}:Broken", "--no-progress"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "strategy 'mypkg.mystrategy:Broken' is refused" in err, err


@pytest.mark.parametrize("command", [
    ["demo", "--turns", "3"],
    ["teach", "--teacher", "scripted", "--turns", "3", "--no-pictures"],
])
def test_the_first_invalid_decision_of_a_plugin_stops_the_episode_in_one_line(mypkg, command, tmp_path, capsys):
    path = tmp_path / "t.jsonl"
    assert make_strategy(f"{mypkg}:BreaksInTheKitchen")  # passes check_strategy's small scenes
    assert main([*command, "--strategy", f"{mypkg}:BreaksInTheKitchen", "--transcript", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.splitlines()[-1].startswith(f"teachbot {command[0]}: strategy 'mypkg.mystrategy:BreaksInTheKitchen' "
                                           "asked LabelQuery(object_index=12, kind='label') on turn 1, which the "
                                           "state refuses (label query object 12 is not an object index"), err
    assert "Traceback" not in err


def test_regress_stops_at_the_first_invalid_decision_of_a_plugin(mypkg, tmp_path, capsys):
    code = main(["regress", "--suite", str(write_suite(tmp_path)), "--results", str(tmp_path / "out"), "--workers",
                 "1", "--strategies", f"{mypkg}:BreaksInTheKitchen", "--no-progress"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and "strategy 'mypkg.mystrategy:BreaksInTheKitchen' asked LabelQuery(" in err, err
    assert "Traceback" not in err
