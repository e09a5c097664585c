"""``teachbot study run``: one participant's sessions, in their assigned order, each followed by the questionnaire.

For each condition not yet done: the instruction screen, the teach session
(the same loop as ``teachbot teach``, resumed from its transcript when it was
interrupted), the questionnaire, and a pause before the next. A person answers
at the terminal; ``simulated`` lets the scripted teacher (with the study's
noise and delay options) play the participant.
"""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import dataclass, field

from dialog.environment import SimulatedKitchen
from dialog.output_paths import check_writable
from dialog.printed_command import command_line
from dialog.session import SessionSettings, open_session
from dialog.study import consent, questionnaire
from dialog.study.atomic import write_atomically
from dialog.study.design import assigned_orders, questionnaire_rng, session_seed
from dialog.study.files import (
    read_transcript_checked,
    session_files,
    session_state_of,
    study_header,
    supersede,
)
from dialog.study.records import expected_session
from dialog.study.studyfile import PRACTICE
from dialog.teachers.terminal import LineReader
from dialog.transcripts.lock import TranscriptLock
from dialog.transcripts.records import TEXT_ACCEPTED, text_problem
from learning.errors import OutputPathError, TranscriptError


@dataclass(frozen=True)
class StudySessionSettings(SessionSettings):
    """A teach session's settings plus the study table every header of the study carries."""

    study: dict = field(default_factory=dict)

    def header(self) -> dict:
        return {**super().header(), "study": dict(self.study)}


def condition_settings(study, participant: str, order: int, condition, simulated: bool) -> StudySessionSettings:
    teacher = {"kind": "scripted", **study.simulated_teacher} if simulated else {"kind": "terminal"}
    return StudySessionSettings(
        task=condition.task, kitchen=condition.kitchen, strategy=condition.strategy,
        seed=session_seed(study, participant, condition.name), turns=condition.turns, budget=condition.budget,
        change_every=condition.change_every, realtime=condition.realtime, fetch_from_pantry=condition.fetch_from_pantry,
        costs=dict(condition.costs), teacher=teacher,
        study=study_header(study, participant, condition.name, order))


class ParticipantRun:
    """The terminal side of one participant's run: what they read, what they type, and the files it writes."""

    def __init__(self, study, participant: str, simulated: bool, input_stream=None, output_stream=None,
                 viewer: bool | None = None, continue_command: str | None = None, show_conditions: bool = False,
                 page=None):
        self.study, self.participant, self.simulated = study, study.check_participant(participant), simulated
        self.order = assigned_orders(study)[participant]
        self.input_stream = input_stream if input_stream is not None else sys.stdin
        self.out = output_stream if output_stream is not None else sys.stdout
        self.reader = LineReader(self.input_stream)
        self.viewer = viewer
        self.continue_command = continue_command or command_line(  # what the "continue with" line says
            ["study", "run", study.path, "--participant", participant] + (["--simulated"] if simulated else []))
        self.show_conditions = show_conditions  # condition names, strategies, budgets: for a pilot only
        self.page = page  # a dialog.web.session.WebPage: the participant answers in the browser
        if page is not None:
            page.teacher.show_budget = show_conditions

    def write(self, text: str, end: str = "\n") -> None:
        print(text, end=end, file=self.out, flush=True)

    def read_line(self):
        return self.reader.readline()

    def states(self) -> list:
        return [session_state_of(self.study, self.participant, position, name)
                for position, name in enumerate(self.order, start=1)]

    def name_at(self, position: int) -> str:
        """The condition at ``position`` (from 1) of the participant's order; 0 is the practice round."""
        return PRACTICE if position == 0 else self.order[position - 1]

    def practice_state(self):
        return session_state_of(self.study, self.participant, 0, PRACTICE)

    def _refuse_damaged(self, position: int, state) -> None:
        which = "the practice round" if position == 0 else f"session {position} ({self.name_at(position)})"
        raise TranscriptError(f"{self.participant} {which} is damaged, so nothing was written: {state.reason}")

    # -- what to run --------------------------------------------------------------------------------------
    def plan(self, only: str | None, again: bool) -> list[int]:
        """The positions to run now; refuses a participant or a condition already done, unless ``again``."""
        states = self.states()
        if only is not None:
            self.study.condition(only)
            position = 0 if only == PRACTICE else self.order.index(only) + 1
            state = self.practice_state() if position == 0 else states[position - 1]
            if state.state == "damaged" and not again:
                self._refuse_damaged(position, state)
            if state.state in ("done", "aborted") and not again:
                raise TranscriptError(f"{self.participant} already did condition '{only}' ({state.state}); "
                                      f"run it again only with --again (the old records are kept, renamed)")
            if again and state.state != "missing":
                files = session_files(self.study, self.participant, position, only)
                lock = TranscriptLock(files.transcript, create=False) if files.transcript.exists() else None
                try:  # not while another process still writes the session
                    moved = supersede(files)
                finally:
                    if lock is not None:
                        lock.release()
                if self.show_conditions:
                    self.write(f"Kept the earlier records as {', '.join(str(p) for p in moved)}.")
                else:  # the file names name the condition; the folder does not
                    self.write(f"Kept the earlier records of session {position} ({len(moved)} files, renamed "
                               f"*.superseded-N in {files.transcript.parent}).")
            return [position]
        if again:
            raise TranscriptError("--again needs --condition NAME: the one condition to run again")
        todo = [position for position, state in enumerate(states, start=1) if state.state not in ("done", "aborted")]
        for position in todo:
            if states[position - 1].state == "damaged":
                self._refuse_damaged(position, states[position - 1])
        if self.study.practice is not None and todo:  # the practice round comes before the first condition
            practice = self.practice_state()
            if practice.state == "damaged":
                self._refuse_damaged(0, practice)
            if practice.state == "running" or (practice.state == "missing"
                                               and all(state.state == "missing" for state in states)):
                todo.insert(0, 0)
        if not todo:
            status = command_line(["study", "status", self.study.path, "--folder", self.study.folder])
            raise TranscriptError(f"{self.participant} has already done every session of study '{self.study.name}' "
                                  f"(see {status}); to run one again: --condition NAME --again")
        return todo

    def abort(self, reason: str) -> int:
        """Mark the participant's current session (the first not done) aborted, with the reason; it stays recorded."""
        if not reason.strip():
            raise TranscriptError("--abort needs a reason, e.g. --abort \"participant felt unwell\"")
        if text_problem(reason):
            raise TranscriptError(f"--abort's reason can't be recorded ({text_problem(reason)}); give {TEXT_ACCEPTED}")
        for position, state in enumerate(self.states(), start=1):
            if state.state in ("done", "aborted"):
                continue
            if state.state == "damaged":
                self._refuse_damaged(position, state)
            name = self.order[position - 1]
            files = session_files(self.study, self.participant, position, name)
            note = {**study_header(self.study, self.participant, name, position), "reason": reason.strip(),
                    "after_turns": state.turns_done, "state_before": state.state}
            check_writable(files.aborted, "abort note")
            write_atomically(files.aborted, json.dumps({"aborted": note}, ensure_ascii=False) + "\n", "abort note",
                             replace=False)
            self.write(f"{self.participant}: session {position} ({name}) marked aborted after {state.turns_done} "
                       f"turns: {reason.strip()}")
            return 0
        raise TranscriptError(f"{self.participant} has no unfinished session to abort")

    # -- running ------------------------------------------------------------------------------------------
    def run(self, only: str | None = None, again: bool = False) -> int:
        positions = self.plan(only, again)
        check_writable(self.study.folder / self.participant, "participant's folder", folder=True)
        order = f" in the order {', '.join(self.order)}" if self.show_conditions else ""
        practice = " (and the practice round first)" if positions[0] == 0 and len(positions) > 1 else ""
        self.write(f"Study '{self.study.name}', participant {self.participant}: {len(self.order)} sessions{order}; "
                   f"{len([p for p in positions if p])} to run now{practice}.")
        agreed = self.ask_consent()
        if agreed is not True:
            return agreed
        for count, position in enumerate(positions):
            if count and positions[count - 1] and not self.simulated:  # no break after the practice round
                self.write(f"\n{self.study.pause}")
                if self.page is not None:
                    self.page.teacher.ask_screen("A short break", self.study.pause, "Go on")
                else:
                    self.read_line()
            stopped = self.run_one(position)
            if stopped is not None:
                return stopped
        self.write(f"{self.participant}: all sessions done for now. Thank you!")
        if self.page is not None:
            self.page.teacher.end("All sessions are done. Thank you!")
        return 0

    def run_one(self, position: int) -> int | None:
        """One session and its questionnaire; None when both are done, else the exit code to stop the run with."""
        name = self.name_at(position)
        condition = self.study.condition(name)
        files = session_files(self.study, self.participant, position, name)
        settings = condition_settings(self.study, self.participant, position, condition, self.simulated)
        state = session_state_of(self.study, self.participant, position, name)
        if state.state == "damaged":
            self._refuse_damaged(position, state)
        title = "Practice round" if position == 0 else (
            f"Session {position} of {len(self.order)}" + (f" ({name})" if self.show_conditions else ""))
        self.write(f"\n=== {title} ===")
        if state.state in ("missing", "running"):
            self.write(condition.instructions.strip())
            interrupted = (f"(This session was interrupted after {state.turns_done} turns; it goes on from there.)"
                           if state.state == "running" else "")
            if interrupted:
                self.write(interrupted)
            if self.page is not None:
                self.page.teacher.ask_screen(title, "\n".join(filter(None, (condition.instructions.strip(),
                                                                              interrupted))), "Begin")
            elif not self.simulated:
                self.write("Press Enter to begin.")
                self.read_line()
            finished = self.teach(files, settings, condition, resume=state.state == "running")
            if not finished:
                self.write(f"Session saved. Continue with: {self.continue_command}")
                return 130 if finished is None else 0
        if position == 0:  # the practice round has no questionnaire
            return None
        if self.study.items and files.questionnaire.exists():
            self.write(f"The questionnaire's answers are already recorded ({files.questionnaire.name}); kept as they "
                       "are.")
        elif self.study.items:
            header = settings.study
            if self.simulated:
                answers = questionnaire.ask_simulated(self.study.items, questionnaire_rng(self.study, self.participant,
                                                                                          name))
            elif self.page is not None:
                answers = questionnaire.ask_web(self.study.items, self.page.teacher)
            else:
                answers = questionnaire.ask_terminal(self.study.items, self.read_line, self.write)
                if answers is None:
                    self.write("The questionnaire was not finished; it is asked again when the run goes on.")
                    return 0
            questionnaire.save(files.questionnaire, header, answers)
            self.write(f"Answers saved ({files.questionnaire.name})." if self.show_conditions else "Answers saved.")
        return None

    def teach(self, files, settings: StudySessionSettings, condition, resume: bool) -> bool | None:
        """Run (or resume) one teach session; True when all its turns are done, False if quit, None if interrupted."""
        lock = TranscriptLock(files.transcript, create=not resume)
        try:
            if resume:
                read_transcript_checked(files, settings.study, expected_session(
                    self.study, self.participant, settings.study["order"], condition))
            elif lock.size() > 0:
                raise TranscriptError(f"{files.transcript} already holds a session")
            return self._teach(files, settings, condition, resume, lock)
        finally:
            lock.release()

    def _teach(self, files, settings, condition, resume: bool, lock) -> bool | None:
        person = not self.simulated
        pictures = None
        if person:
            try:
                pictures = check_writable(files.pictures, "scene pictures", folder=True)
            except OutputPathError as error:
                self.write(f"warning: {error}; going on without scene pictures")
        environment = SimulatedKitchen(task=settings.task, kitchen=settings.kitchen, seed=settings.seed,
                                       pictures=pictures is not None)
        viewer = None
        try:
            from dialog.viewer import start_viewer, stop_viewer

            want_viewer = condition.viewer if self.viewer is None else self.viewer
            if self.page is not None:  # the page shows this session's kitchen (its 3D view unless --no-viewer)
                self.page.teacher.new_session()  # and only this session's conversation
                self.page.three_d = self.viewer is not False
                self.page.attach(environment)
            elif want_viewer and person:
                viewer = start_viewer(argparse.Namespace(viewer=True, viewer_export=None), environment.world)
            observers = self.page.observers if self.page is not None else () if viewer is None else (viewer,)
            manager, records = open_session(settings, environment, files.transcript, resume=resume,
                                            pictures=None if pictures is None else str(pictures),
                                            input_stream=self.input_stream, output_stream=self.out,
                                            observers=observers, lock=lock,
                                            teacher=None if self.page is None else self.page.teacher)
            if self.page is not None and records:  # a resumed session: the page shows the conversation so far
                self.page.teacher.recall(records, environment.concepts, environment.feature_names)
            if person and self.page is None:
                manager.teacher.reader = self.reader  # one reader for the whole run: nothing typed is lost
                manager.teacher.show_budget = self.show_conditions
                self.write("Type 'help' at any question for what you can answer; 'why' asks the robot's reason, "
                           "'undo' takes back your last answer, 'quit' saves and stops.")
            manager.say = self._narrator(manager.teacher, person)
            try:
                result = manager.run(replay=records)
            except KeyboardInterrupt:
                self.write("\nInterrupted; the session is saved.")
                return None
            finally:
                manager.transcript.close()
            if self.show_conditions:
                self.write(f"Session over: held-out accuracy {result.accuracy:.1%}, {result.completed} of "
                           f"{result.turns} turns, budget spent {result.budget_spent:g} of {settings.budget:g}.")
            else:  # accuracy and budget are for the researcher (study report)
                self.write(f"Session over: {result.completed} of {result.turns} turns.")
            return result.completed >= result.turns
        finally:
            if viewer is not None:
                stop_viewer(viewer)
            if self.page is not None:
                self.page.detach()
            environment.close()

    def ask_consent(self) -> bool | int:
        """The consent text, before anything is recorded: True once agreed (now or in an earlier run), else the
        exit code to stop with (0: declined, with only the declined note recorded; 1: no answer could be read)."""
        study, participant = self.study, self.participant
        if study.consent is None or consent.consent_path(study, participant).exists():
            return True  # agreed once (a damaged record was refused with the sessions it marks damaged)
        check_writable(consent.consent_path(study, participant), "consent record")
        if self.simulated:
            consent.record_agreed(study, participant, "simulated")
            self.write("Consent: not asked in a simulated run; the consent record says simulated.")
            return True
        if self.page is not None:
            choice = self.page.teacher.ask_choice("Before we begin", study.consent.text.strip() + "\n"
                                                  + consent.QUESTION, (consent.AGREE, consent.DECLINE))
            agreed = choice == consent.AGREE
        else:
            self.write("\n" + study.consent.text.strip() + f"\n\n{consent.QUESTION} Type 'yes' or 'no'.")
            agreed = None
            while agreed is None:
                self.write("> ", end="")
                line = self.read_line()
                if line is None:
                    self.write("\nNo answer to the consent question (standard input ended): nothing was recorded. "
                               "Run study run where the participant can answer (at a terminal, or with --web).")
                    return 1
                agreed = {"yes": True, "y": True, "no": False, "n": False}.get(line.strip().lower())
                if agreed is None:
                    self.write("Please type 'yes' to take part or 'no' not to.")
        if not agreed:
            path = consent.record_declined(study, participant)
            self.write(f"{participant} did not agree to take part: nothing is recorded but the note {path.name}; "
                       "the run ends.")
            if self.page is not None:
                self.page.teacher.end("You chose not to take part. Nothing was recorded. Thank you for your time.")
            return 0
        path = consent.record_agreed(study, participant, "page" if self.page is not None else "terminal")
        self.write(f"Consent recorded ({path.name}).")
        return True

    def _narrator(self, teacher, person: bool):
        def say(text: str) -> None:
            if not person:
                return  # a simulated run prints one line per session
            if text.startswith("Turn") and "stays quiet" not in text and "ended the session" not in text:
                return
            if "stays quiet" in text and not self.show_conditions:  # its reason may name the budget
                text = text.split(" (", 1)[0]
            teacher.say(text)
        return say
