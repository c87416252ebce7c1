"""How a round reads on screen: the question and, once revealed, the distribution and the answer.

HTML with its own sizes (the question at 19 px, the rest at 17 px, never under 16 px) and
colours of at least 4.5:1 contrast on the panel's white (text #1b1b1b, bars #1f4fa0, the right
answer #0b6b2f), so that it reads on a projector from the back row. Every text is escaped: a
question may come from the lecturer's keyboard; a lesson's ``*emphasis*`` and ``**bold**`` are
kept as such.
"""

from __future__ import annotations

import html
import re

from .rounds import CHOICE, CLOSED, OPEN, REVEALED, Round

TEXT, BAR, RIGHT, MUTED = "#1b1b1b", "#1f4fa0", "#0b6b2f", "#4a4a4a"  # 15.9, 8.4, 6.9 and 8.9 : 1 on white
BOX = f'<div style="font-size:17px;line-height:1.4;color:{TEXT};margin:4px 12px 8px 12px">{{}}</div>'


def inline(text: str) -> str:
    """``text`` escaped, with a lesson's **bold** and *emphasis* as HTML."""
    t = html.escape(text)
    t = re.sub(r"\*\*(.+?)\*\*", r"<b>\1</b>", t)
    return re.sub(r"(?<![*\w])\*(?!\s)(.+?)(?<!\s)\*(?![*\w])", r"<i>\1</i>", t)


def _question(r: Round) -> str:
    q = r.question
    out = [f'<div style="font-size:19px;font-weight:600;margin-bottom:4px">Round {r.number}: {inline(q.text)}</div>']
    if q.kind == CHOICE:
        out += [f"<div><b>{letter}.</b> {html.escape(c)}</div>" for letter, c in zip(q.letters, q.choices)]
    else:
        unit = f" in {html.escape(q.unit)}" if q.unit else ""
        out.append(f'<div style="color:{MUTED}">Answer with a number{unit}.</div>')
    return "".join(out)


def _bars(r: Round, right: str | None) -> str:
    counts = r.counts()
    total = max(len(r.answers), 1)
    most = max([c for _, c in counts] + [1])
    rows = []
    for label, c in counts:
        good = right is not None and (label.split(". ", 1)[-1] == right if r.question.kind == CHOICE else False)
        colour = RIGHT if good else TEXT
        mark = " ✓" if good else ""
        width = 100.0 * c / most
        rows.append(f'<div style="margin:5px 0;color:{colour}"><div>{html.escape(label)}{mark} · <b>{c}</b> '
                    f'({100.0 * c / total:.0f} %)</div><div style="background:{RIGHT if good else BAR};height:12px;'
                    f'width:{width:.1f}%;min-width:2px;border-radius:2px"></div></div>')
    return "".join(rows)


def _answer(r: Round) -> str:
    q = r.question
    median = r.median()
    parts = []
    if q.answer is not None:
        parts.append(f'<div style="color:{RIGHT};font-weight:600;margin-top:6px">Answer: '
                     f"{html.escape(q.label(q.answer))}</div>")
    if median is not None:
        parts.append(f"<div>Median of the class: {html.escape(q.label(median))}</div>")
    if q.source:
        parts.append(f'<div style="color:{MUTED};font-size:16px">{html.escape(q.source)}</div>')
    return "".join(parts)


def _count(r: Round) -> str:
    n = len(r.answers)
    return f"{n} answer{'' if n == 1 else 's'}"


def _note(text: str) -> str:
    return f'<div style="color:{MUTED};margin-top:4px">{html.escape(text)}</div>'


def class_html(r: Round | None) -> str:
    """What every class tab shows of round ``r``: the question while it is open, the results once revealed."""
    if r is None:
        return ""
    if r.state == OPEN:
        body = _question(r) + _note(f"{_count(r)} so far: answer below.")
    elif r.state == CLOSED:
        body = _question(r) + _note(f"Closed with {_count(r)}: the answer comes next.")
    else:
        right = r.question.answer if isinstance(r.question.answer, str) else None
        body = _question(r) + f"<div style=\"margin-top:6px\">{_count(r)}:</div>" + _bars(r, right) + _answer(r)
    return BOX.format(body)


def lecturer_html(r: Round | None) -> str:
    """What the lecturer's tab shows of round ``r``: the count and the distribution as they come."""
    if r is None:
        return ""
    state = {OPEN: "open", CLOSED: "closed", REVEALED: "revealed to the class"}[r.state]
    right = r.question.answer if isinstance(r.question.answer, str) else None
    body = (_question(r) + f'<div style="margin-top:6px"><b>{_count(r)}</b> · {state}</div>' + _bars(r, right)
            + (_answer(r) if r.state == REVEALED else ""))
    return BOX.format(body)
