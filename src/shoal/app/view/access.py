"""What a screen reader gets of a tab: a name for every control, the status announced, a title.

viser labels a control's row (``<label for=…>``) but not what a reader lands on inside it: a
slider's thumb, the number box beside it, a number box's ▲▼ steppers, an icon button. The page
script (:data:`ACCESS_JS`) names each from its row's label whenever the panel changes
("omega ω", "omega ω, number", "seed: increase"), and folder headers become buttons with
``aria-expanded``.

The status line changes four times a second while a run plays, far too often to read out, so
it is not itself a live region: :class:`Announcer` copies it into a hidden ``aria-live="polite"``
region (``#shoal-live``, role status) when what it says changes in kind (playing, paused,
finished, a new scene) and otherwise at most once every :data:`ANNOUNCE_SECONDS`. The page's
title names the scene: "Shoal · <preset>".
"""

from __future__ import annotations

import json
import re
import time
from typing import Any

from .script import run_script

ANNOUNCE_SECONDS = 20.0  # the status read out at most this often while nothing changes in kind
TITLE = "Shoal · {name}"

ACCESS_JS = """
(() => {
  const P = window.__shoalPage || (window.__shoalPage = {});
  if (P.accessInstalled) return;
  P.accessInstalled = true;
  const live = document.createElement("div");
  live.id = "shoal-live";
  live.setAttribute("role", "status");
  live.setAttribute("aria-live", "polite");
  live.setAttribute("aria-atomic", "true");
  live.style.cssText = "position:absolute;width:1px;height:1px;margin:-1px;padding:0;overflow:hidden;" +
                       "clip:rect(0 0 0 0);white-space:nowrap;border:0";
  document.body.appendChild(live);
  P.announce = (text) => { live.textContent = text; };
  P.title = (text) => { document.title = text; P.wantTitle = text; };
  const named = (el) => el.getAttribute("aria-label") || el.getAttribute("aria-labelledby") ||
    (el.id && document.querySelector(`label[for="${CSS.escape(el.id)}"]`)) || (el.textContent || "").trim();
  const name = (el, text) => { if (!named(el)) el.setAttribute("aria-label", text); };
  const ICONS = {"tabler-icon-adjustments-horizontal": "display settings", "tabler-icon-x": "close",
                 "tabler-icon-chevron-down": "open", "tabler-icon-chevron-up": "close"};
  const run = () => {
    P.namePending = false;
    for (const label of document.querySelectorAll("label[for]")) {
      const text = label.textContent.replace(/\\s+/g, " ").trim();
      if (!text) continue;
      const row = label.closest(".mantine-Flex-root");
      if (!row) continue;
      for (const t of row.querySelectorAll('[role="slider"]')) name(t, text);
      const inputs = [...row.querySelectorAll("input:not([type=hidden]):not([type=file])")];
      const paired = inputs.length > 1 || row.querySelector('[role="slider"]');
      for (const i of inputs) if (!named(i)) i.setAttribute("aria-label", paired ? `${text}, number` : text);
      for (const b of row.querySelectorAll(".mantine-NumberInput-control")) {
        const up = b.getAttribute("data-direction") === "up" || b === b.parentElement.firstElementChild;
        name(b, `${text}: ${up ? "increase" : "decrease"}`);
      }
    }
    for (const b of document.querySelectorAll("button, [role=button]")) {
      if (named(b)) continue;
      const icon = b.querySelector("svg[class*='tabler-icon-']");
      const cls = icon ? [...icon.classList].find((c) => c.startsWith("tabler-icon-") && c !== "tabler-icon") : "";
      name(b, ICONS[cls] || (cls ? cls.replace("tabler-icon-", "").replace(/-/g, " ") : "button"));
    }
    // folder headers: a button that says whether it is open
    for (const f of document.querySelectorAll(".mantine-Paper-root > div:first-child")) {
      if (!f.querySelector(":scope > svg, :scope > .tabler-icon") || f.getAttribute("role")) continue;
      f.setAttribute("role", "button");
      f.tabIndex = 0;
      f.addEventListener("keydown", (e) => {
        if (e.key === "Enter" || e.key === " ") { e.preventDefault(); f.click(); }
      });
    }
    if (P.wantTitle && document.title !== P.wantTitle) document.title = P.wantTitle;
  };
  new MutationObserver(() => {
    if (P.namePending) return;
    P.namePending = true;
    setTimeout(run, 150);
  }).observe(document.body, {childList: true, subtree: true});
  run();
})();
"""


def access_script() -> str:
    return ACCESS_JS


def _plain(markdown: str) -> str:
    """The status line's markdown as the words a reader says (no markup, no light-drawing note)."""
    text = markdown.split("<br>")[0]
    text = re.sub(r"<[^>]+>", " ", text)
    text = re.sub(r"[*_`]", "", text).replace("\\", "")
    return " ".join(text.split())


def _kind(text: str) -> str:
    """What a status line says in kind: its scene and its state, without the numbers."""
    words = [w for w in text.split(" · ")[:2]]
    return " · ".join(re.sub(r"[-+]?\d[\d.,]*", "#", w) for w in words)


class Announcer:
    """The status line, read out through the page's live region, at most every
    :data:`ANNOUNCE_SECONDS` unless it changed in kind; and the page's title."""

    def __init__(self, api: Any, clock: Any = time.monotonic) -> None:
        self.api, self.clock = api, clock
        self.said = ""
        self.said_kind = ""
        self.at = -float("inf")
        self.title = ""

    def _run(self, source: str) -> None:
        run_script(self.api, source)

    def status(self, markdown: str) -> bool:
        """The status line now shows ``markdown``: announce it if due. True if it was sent."""
        text = _plain(markdown)
        kind, now = _kind(text), self.clock()
        if text == self.said or (kind == self.said_kind and now - self.at < ANNOUNCE_SECONDS):
            return False
        self.said, self.said_kind, self.at = text, kind, now
        self._run(f"window.__shoalPage && window.__shoalPage.announce && "
                  f"window.__shoalPage.announce({json.dumps(text)});")
        return True

    def name(self, scene: str) -> None:
        """The page's title for ``scene`` (sent only when it changes)."""
        title = TITLE.format(name=scene)
        if title != self.title:
            self.title = title
            self._run(f"window.__shoalPage && window.__shoalPage.title && "
                      f"window.__shoalPage.title({json.dumps(title)});")
