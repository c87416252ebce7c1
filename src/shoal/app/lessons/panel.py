"""The Lessons tab: pick a lesson, walk its steps, set up each step's scene, reveal answers; and
the Fig. 9-1 chooser below it.

Self-contained: it needs a viser GUI handle (``client.gui``; build it inside the tab or folder it
should fill) and two callbacks from its host:

- ``set_up(preset, values) -> errors``: load ``preset`` with field ``values`` (dotted path →
  value) through the app's validated path, best paused at step 0 so that the student predicts
  before pressing Play; an empty list means done, else the refusal's messages;
- ``notify(title, body, color)``: a toast;
- optionally ``measure(preset, values, metrics)``: the run on screen (:class:`.readings.Run`)
  if it is that scene, else why not. With it, a step whose ``check`` names metrics lists
  them under its question as they read on screen (:meth:`LessonsPanel.refresh`, which the host
  calls a few times a second).

Where the student is (lesson, step, answer shown, chooser answers) lives in a
:class:`LessonProgress` the host keeps, so a panel rebuilt by the host (a *Set up* that loads
another kind of scene) opens where the old one was. While a *Set up* runs,
``progress.focus`` is true: a host that rebuilds its tabs then can put this one first.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass, field
from typing import Any, Callable

from . import chooser, library, readings
from .chooser import MAX_ANSWERS, Leaf, Question, Tree
from .model import Lesson
from .parse import LessonError
from .readings import Measure
from .scenes import describe

SetUp = Callable[[str, dict[str, Any]], list[str]]
Ask = Callable[[Lesson, int], None]  # ask a class step ``index``'s question (a lecture's round)
Notify = Callable[[str, str, str], None]
NAV = ("◀ Back", "Next ▶")
CHOOSER_NAV = ("◀ Back", "Start over")
INTRO = ("Set up a step, read its question, predict, press **Play**, then reveal the answer. The numbers "
         "a step asks about are read out under its question as the run goes.")


@dataclass
class LessonProgress:
    """Where one student is; kept by the host across rebuilds of the panel."""

    lesson: str | None = None  # lesson id (None: the first lesson)
    step: int = 0  # 0..len(steps); len(steps) is the "try it yourself" page
    revealed: bool = False
    choices: list[int] = field(default_factory=list)  # chooser answers so far (0-based)
    focus: bool = False  # a Set up is running: a rebuilt host shows this panel first


class LessonsPanel:
    """The lessons and the chooser, built on ``gui`` (see the module docstring)."""

    def __init__(self, gui: Any, set_up: SetUp, notify: Notify, progress: LessonProgress | None = None,
                 lessons: dict[str, Lesson] | None = None, tree: Tree | None = None,
                 measure: Measure | None = None, ask: Ask | None = None) -> None:
        self.gui, self._set_up, self.notify, self._measure, self._ask = gui, set_up, notify, measure, ask
        self.progress = progress if progress is not None else LessonProgress()
        problems: tuple[str, ...] = ()
        if lessons is None:
            lessons, problems = library.shipped()
        if tree is None:
            try:
                tree = chooser.shipped_tree()
            except LessonError as err:
                problems += tuple(err.messages)
        self.lessons, self.tree = lessons, tree
        self.closed = False
        self._lock = threading.Lock()
        p = self.progress
        if p.lesson not in self.lessons:
            p.lesson, p.step, p.revealed = next(iter(self.lessons), None), 0, False
        self._build(problems)
        self._show_lesson()
        self._show_chooser()

    # ------------------------------------------------------------------ building
    def _build(self, problems: tuple[str, ...]) -> None:
        gui = self.gui
        gui.add_markdown(INTRO)
        self._labels = {lesson.label: lid for lid, lesson in self.lessons.items()}
        current = self.lessons[self.progress.lesson].label if self.progress.lesson else ""
        self.lesson_menu = gui.add_dropdown("lesson", tuple(self._labels) or ("(no lessons)",),
                                            initial_value=current or "(no lessons)",
                                            hint="one lesson per chapter; the Fig. 9-1 chooser is below")
        self.summary = gui.add_markdown("")
        self.nav = gui.add_button_group("step", NAV)
        self.step_text = gui.add_markdown("")
        self.setup_button = gui.add_button("Set up this step", color="green",
                                           hint="load this step's scene from its start")
        self.setup_text = gui.add_markdown("")
        self.instruction = gui.add_markdown("")
        self.question = gui.add_markdown("")
        self.ask_button = gui.add_button("Ask the class", color="violet", visible=False,
                                         hint="open this question as a round: every class tab answers, "
                                              "then you reveal") if self._ask is not None else None
        self.readings = gui.add_markdown("", visible=False)
        self.answer_button = gui.add_button("Show answer", hint="predict first, then check")
        self.answer = gui.add_markdown("", visible=False)
        with gui.add_folder("Which algorithm? (thesis Fig. 9-1)", expand_by_default=False):
            self.chooser_text = gui.add_markdown("")
            self.choice_buttons = [gui.add_button(f"answer {i + 1}", visible=False) for i in range(MAX_ANSWERS)]
            self.open_button = gui.add_button("Open this scene", color="green", visible=False)
            self.chooser_nav = gui.add_button_group("chooser", CHOOSER_NAV)
        if problems:
            gui.add_markdown("*Not shown (bad lesson files):*\n\n" + "\n".join(f"- {m}" for m in problems[:8]))
        self._wire()

    def _wire(self) -> None:
        @self.lesson_menu.on_update
        def _(event: Any) -> None:
            self._handle(self._pick_lesson, self.lesson_menu.value)

        @self.nav.on_click
        def _(event: Any) -> None:
            self._handle(self._move, -1 if event.target.value == NAV[0] else 1)

        @self.setup_button.on_click
        def _(event: Any) -> None:
            self._handle(self._set_up_step)

        @self.answer_button.on_click
        def _(event: Any) -> None:
            self._handle(self._toggle_answer)

        if self.ask_button is not None:
            @self.ask_button.on_click
            def _(event: Any) -> None:
                self._handle(self._ask_class)

        for i, button in enumerate(self.choice_buttons):
            button.on_click(lambda event, i=i: self._handle(self._choose, i))

        @self.open_button.on_click
        def _(event: Any) -> None:
            self._handle(self._open_leaf)

        @self.chooser_nav.on_click
        def _(event: Any) -> None:
            self._handle(self._chooser_back, event.target.value == CHOOSER_NAV[1])

    def close(self) -> None:
        """The host took this panel's handles off the page: ignore what is still in flight."""
        self.closed = True

    def _handle(self, action: Callable[..., None], *args: Any) -> None:
        with self._lock:
            if not self.closed:
                action(*args)

    # ------------------------------------------------------------------ lessons
    @property
    def lesson(self) -> Lesson | None:
        return self.lessons.get(self.progress.lesson or "")

    def _pick_lesson(self, label: str) -> None:
        lid = self._labels.get(label)
        if lid is None or lid == self.progress.lesson:
            return
        self.progress.lesson, self.progress.step, self.progress.revealed = lid, 0, False
        self._show_lesson()

    def _move(self, delta: int) -> None:
        lesson = self.lesson
        if lesson is None:
            return
        step = min(max(self.progress.step + delta, 0), len(lesson.steps))
        if step != self.progress.step:
            self.progress.step, self.progress.revealed = step, False
            self._show_lesson()

    def _toggle_answer(self) -> None:
        self.progress.revealed = not self.progress.revealed
        self._show_answer()

    def _ask_class(self) -> None:
        lesson = self.lesson
        if self._ask is not None and lesson is not None and self.progress.step < len(lesson.steps):
            self._ask(lesson, self.progress.step)

    def _set_up_step(self) -> None:
        lesson = self.lesson
        if lesson is None or self.progress.step >= len(lesson.steps):
            return
        scene = lesson.scene(self.progress.step)
        if scene is not None:
            self._load(*scene, what=f"step {self.progress.step + 1}: {lesson.steps[self.progress.step].title}")

    def _load(self, preset: str, values: dict[str, Any], what: str) -> None:
        """Ask the host to load the scene; the host may rebuild (and close) this panel."""
        self.progress.focus = True
        try:
            errors = self._set_up(preset, values)
        finally:
            self.progress.focus = False
        if errors:
            self.notify("Refused: lesson set-up", "\n".join(errors[:6]), "red")
        else:
            self.notify(f"Set up {what}", f"{describe(preset, values)}. Press Play when ready.", "green")

    def _show_lesson(self) -> None:
        lesson, p = self.lesson, self.progress
        if lesson is None:
            self.summary.content = "No lessons are installed."
            for h in (self.nav, self.setup_button, self.answer_button):
                h.visible = False
            return
        intro = f"\n\n{lesson.intro}" if lesson.intro else ""
        self.summary.content = f"*{lesson.summary}*{intro}"
        self.summary.visible = p.step == 0  # the lesson's opening, then only the steps
        n = len(lesson.steps)
        if p.step >= n:
            self.step_text.content = ("#### Try it yourself\n\n"
                                      + "\n".join(f"- {idea}" for idea in lesson.try_it))
            for h in (self.setup_button, self.setup_text, self.instruction, self.question, self.answer_button,
                      self.answer, self.readings, self.ask_button):
                if h is not None:
                    h.visible = False
            return
        step = lesson.steps[p.step]
        self.step_text.content = f"#### Step {p.step + 1} of {n}: {step.title}\n\n{step.text}"
        scene = lesson.scene(p.step)
        self.setup_button.visible = self.setup_text.visible = scene is not None
        if scene is not None:
            self.setup_text.content = f"<small>Loads {describe(*scene)}.</small>"
        self.instruction.content = f"**Do:** {step.instruction}"
        self.question.content = f"**Question:** {step.question}"
        self.answer.content = f"**Answer:** {step.answer}"
        for h in (self.instruction, self.question, self.answer_button):
            h.visible = True
        if self.ask_button is not None:
            self.ask_button.visible = step.round is not None
        self._show_answer()
        self._show_readings()

    def refresh(self) -> None:
        """Read the step's numbers off the run on screen again (the host calls this a few
        times a second; a handle is sent only when its text changed)."""
        with self._lock:
            if not self.closed:
                self._show_readings()

    def _show_readings(self) -> None:
        lesson = self.lesson
        found = readings.step_check(lesson, self.progress.step) if lesson is not None else None
        if found is None or self._measure is None:
            self.readings.visible = False
            return
        (preset, values), check = found
        run = self._measure(preset, values, readings.names(check))
        if isinstance(run, str):
            content = f"**Read on screen:** *{run}*"
        else:
            content = readings.text(readings.read(check, run), run.k)
        if self.readings.content != content:
            self.readings.content = content
        if not self.readings.visible:
            self.readings.visible = True

    def _show_answer(self) -> None:
        self.answer.visible = self.progress.revealed
        self.answer_button.label = "Hide answer" if self.progress.revealed else "Show answer"

    # ------------------------------------------------------------------ chooser
    def _node(self) -> Question | Leaf | None:
        if self.tree is None:
            return None
        try:
            return chooser.walk(self.tree, self.progress.choices)
        except IndexError:  # answers from another tree: start over
            self.progress.choices = []
            return chooser.walk(self.tree, [])

    def _choose(self, i: int) -> None:
        node = self._node()
        if isinstance(node, Question) and i < len(node.answers):
            self.progress.choices.append(i)
            self._show_chooser()

    def _chooser_back(self, restart: bool) -> None:
        if restart:
            self.progress.choices = []
        elif self.progress.choices:
            self.progress.choices.pop()
        self._show_chooser()

    def _open_leaf(self) -> None:
        node = self._node()
        if isinstance(node, Leaf):
            self._load(node.preset, dict(node.values), what=node.title)

    def _show_chooser(self) -> None:
        node, tree = self._node(), self.tree
        if node is None or tree is None:
            self.chooser_text.content = "The chooser is not installed."
            return
        trail = " → ".join(chooser.trail(tree, self.progress.choices))
        head = f"<small>{trail}</small>\n\n" if trail else f"{tree.about}\n\n"
        if isinstance(node, Question):
            detail = f"\n\n{node.detail}" if node.detail else ""
            self.chooser_text.content = f"{head}**{node.question}**{detail}"
            for i, button in enumerate(self.choice_buttons):
                button.visible = i < len(node.answers)
                if i < len(node.answers):
                    button.label = node.answers[i].label
            self.open_button.visible = False
        else:
            self.chooser_text.content = (f"{head}#### {node.title}\n\n*Chapter {node.chapter}* · scene "
                                         f"`{node.preset}`\n\n{node.why}")
            for button in self.choice_buttons:
                button.visible = False
            self.open_button.visible = True
            self.open_button.label = f"Open {node.preset}"
