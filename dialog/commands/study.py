"""``teachbot study run|status|report STUDY.toml``: user studies with participants, conditions and questionnaires."""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

from dialog.printed_command import command_line


def register(subparsers) -> None:
    parser = subparsers.add_parser("study", help="run a user study: participants, conditions, questionnaires, report",
                                   description="Run a user study described by a study file (docs/studies.md).")
    actions = parser.add_subparsers(dest="study_action", required=True, metavar="ACTION")

    run = actions.add_parser(
        "run", help="run one participant's sessions in their assigned order",
        description="Run one participant's teaching sessions, one condition after another in the order the study "
                    "assigns them, each followed by its questionnaire; --simulated lets a scripted teacher play "
                    "the participant, to dry-run a study.")
    _study_arguments(run)
    run.add_argument("--participant", required=True, metavar="ID", help="the participant's id (never a name)")
    run.add_argument("--condition", default=None, metavar="NAME", help="run only this condition")
    run.add_argument("--again", action="store_true",
                     help="with --condition: run a condition already done again (the old records are kept, renamed)")
    run.add_argument("--abort", default=None, metavar="REASON",
                     help="mark the participant's current session aborted with REASON (it stays in the record)")
    run.add_argument("--no-viewer", action="store_true", help="no meshcat viewer, whatever the conditions say")
    run.add_argument("--show-conditions", action="store_true",
                     help="show the participant the condition names, the order and the budgets (for a pilot; by "
                          "default they see 'Session 1 of 3' and the instructions only)")
    from dialog.web.session import add_web_options

    add_web_options(run, "the participant answers")
    run.set_defaults(handler=_run)

    status = actions.add_parser(
        "status", help="who has done what, what is missing or aborted, are orders balanced",
        description="List every participant's sessions (done, running, questionnaire, aborted, missing) and say "
                    "whether the orders of those who finished are balanced.")
    _study_arguments(status)
    status.set_defaults(handler=_status)

    report = actions.add_parser(
        "report", help="tidy CSV tables, a Markdown report with tests, and PNG plots",
        description="Write the study's recorded turns and questionnaire answers as tidy CSV tables, a Markdown "
                    "report with significance tests between conditions, and PNG plots.")
    _study_arguments(report)
    report.add_argument("--out", type=Path, default=None, metavar="DIR",
                        help="where the report goes (default: <study folder>/report)")
    report.add_argument("--allow-mixed", action="store_true",
                        help="report a folder that holds both simulated and real sessions (rows say which)")
    report.set_defaults(handler=_report)


def _study_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("study", type=Path, metavar="STUDY.toml", help="the study file")
    parser.add_argument("--folder", type=Path, default=None, metavar="DIR",
                        help="the study's records folder (default: the study file's 'folder', or "
                             f"'<folder>{SIMULATED_SUFFIX}' with --simulated)")
    parser.add_argument("--simulated", action="store_true",
                        help="a dry run: a scripted teacher (the study's noise and delay models) plays the "
                             f"participant, and the records go to '<folder>{SIMULATED_SUFFIX}' unless --folder says")


SIMULATED_SUFFIX = "-simulated"  # dry runs keep out of the folder where real participants' records go
# run's options that its records do not hold, repeated by its "continue with" line (--again would supersede again)
RUN_OPTIONS = (("--folder", "folder"), ("--simulated", "simulated"), ("--condition", "condition"),
               ("--no-viewer", "no_viewer"))


def _load(args):
    from dialog.study.studyfile import load_study

    study = load_study(args.study)
    if args.folder is not None:
        study = dataclasses.replace(study, folder=args.folder)
    elif args.simulated:
        study = dataclasses.replace(study, folder=study.folder.with_name(study.folder.name + SIMULATED_SUFFIX))
    return dataclasses.replace(study, simulated=args.simulated)


def _run(args) -> int:
    from dialog.commands._resume import continue_command
    from dialog.study.run import ParticipantRun
    from dialog.web.session import check_web_options, web_continue_options
    from learning.errors import SettingsError, TeachbotError

    check_web_options(args)
    if args.web and (args.simulated or args.abort is not None):
        raise SettingsError(f"--web is for a participant answering in the page; not with "
                            f"{'--simulated' if args.simulated else '--abort'}")
    study = _load(args)
    again = continue_command(["study", "run", args.study, "--participant", args.participant], args,
                             RUN_OPTIONS + web_continue_options(args))
    viewer = False if args.no_viewer else None
    if args.abort is not None or not args.web:
        runner = ParticipantRun(study, args.participant, args.simulated, viewer=viewer,
                                show_conditions=args.show_conditions, continue_command=again)
        return runner.abort(args.abort) if args.abort is not None else runner.run(args.condition, args.again)
    from dialog.web.session import WebPage

    runner = ParticipantRun(study, args.participant, False, viewer=viewer, show_conditions=args.show_conditions,
                            continue_command=again)
    if not args.again:
        runner.plan(args.condition, False)  # refuses a participant already done before the page opens
    page = WebPage(args)  # the participant's title: the study's name is the researcher's
    ending = ""  # the runner's "All sessions are done", or why the run stopped
    try:
        runner.page = page
        page.teacher.show_budget = args.show_conditions
        code = runner.run(args.condition, args.again)
        if not page.teacher.ended:  # quit, Ctrl-C
            ending = "The run stopped. What is done is saved; it goes on from there when it is started again."
        return code
    except TeachbotError:  # a full disk, a damaged record: the terminal says what; the page, that it stopped
        ending = "The run stopped because of a problem on the computer. What is done is saved."
        raise
    except KeyboardInterrupt:
        ending = "The run was interrupted. What is done is saved; it goes on from there when it is started again."
        raise
    finally:
        page.close(ending)


def _dry_run_note(args, study, action: str) -> str:
    """One line when the study's records folder holds no session but its dry-run folder does: where the
    simulated sessions are, and the exact command that reads them ('' otherwise)."""
    if args.simulated or args.folder is not None or any(study.folder.glob("*/*.jsonl")):
        return ""
    dry = study.folder.with_name(study.folder.name + SIMULATED_SUFFIX)
    if not any(dry.glob("*/*.jsonl")):
        return ""
    command = command_line(["study", action, args.study, "--simulated"])
    return (f"note: no session is recorded in {study.folder}; the simulated sessions (study run --simulated) are "
            f"in {dry}: {command}")


def _status(args) -> int:
    from dialog.study.status import status_text

    study = _load(args)
    print(status_text(study), flush=True)
    note = _dry_run_note(args, study, "status")
    if note:
        print(note, flush=True)
    return 0


def _report(args) -> int:
    from dialog.study.report import write_report

    study = _load(args)
    written = write_report(study, args.out or study.folder / "report", allow_mixed=args.allow_mixed)
    for path in written:
        print(path)
    note = _dry_run_note(args, study, "report")
    if note:
        print(note, flush=True)
    return 0
