"""The labels over the arena: never under the page's smallest text, and a lecture class's labels
kept whole in one element (``shoal.app.view.overlay``; the page side: tests/browser/test_browser_class_labels.py)."""

from __future__ import annotations

import json
from html.parser import HTMLParser

from hypothesis import given
from hypothesis import strategies as st

from shoal.app.view.overlay import HOLDER, LABEL_PX, ClassLabels, Labels, label_px
from shoal.app.view.projector import MIN_PX


def held(markup: str) -> dict:
    """The state a page reads from ``ClassLabels.holder_html()``: the holder's attribute, parsed as a browser does."""
    found: list[dict] = []

    class Reader(HTMLParser):
        def handle_starttag(self, tag, attrs):
            a = dict(attrs)
            if HOLDER in a:
                assert "hidden" in a, "the holder shows nothing"
                found.append(json.loads(a[HOLDER]))

    Reader().feed(markup)
    assert len(found) == 1
    return found[0]


def test_no_label_is_smaller_than_the_pages_smallest_text():
    assert label_px(0.85) == MIN_PX  # the colour bar's ticks: 11.05 px before
    assert label_px(1.0) == LABEL_PX
    assert label_px(1.1) == round(LABEL_PX * 1.1, 2)


def test_a_tabs_labels_ask_the_page_for_the_floor_too():
    sent: list[str] = []
    labels = Labels(None)
    labels._run = sent.append  # (what would go to the page)
    labels.put("/a/tick", "40", "center-left", 0.85, True)
    assert f'label("/a/tick", "40", "center-left", {float(MIN_PX)}, true)' in sent[0], sent[0]


def test_class_labels_merge_changes_and_count_only_real_ones():
    c = ClassLabels()
    c.put("/a/source", "source", "top-left", 1.0, True)
    assert c.revision == 1
    c.put("/a/source", "source")  # the same: no change
    assert c.revision == 1
    c.put("/a/source", shown=False)  # a part changes, the rest stays
    assert c.state["/a/source"] == ["source", "top-left", LABEL_PX, False] and c.revision == 2
    c.put("/a/scale", "5 m", "center-left", 1.1, True)
    c.drop(["/a/source", "/a/gone"])
    assert list(c.state) == ["/a/scale"] and c.revision == 4
    assert held(c.holder_html()) == {"/a/scale": ["5 m", "center-left", label_px(1.1), True]}


ANY_TEXT = st.text(st.characters(exclude_categories=()), max_size=60)  # lone surrogates too


@given(ANY_TEXT, ANY_TEXT)
def test_any_text_comes_back_to_the_page_as_the_same_text(name, text):
    c = ClassLabels()
    c.put(name, text, "top-left", 1.0, True)
    markup = c.holder_html()
    markup.encode("utf-8")  # (what viser sends: a lone surrogate would not encode)
    assert held(markup) == {name: [text, "top-left", LABEL_PX, True]}


def test_a_hostile_text_stays_inside_the_holders_attribute():
    c = ClassLabels()
    c.put("/x", '"><script>alert(1)</script><div data-shoal-labels="{}">', "top-left", 1.0, True)
    markup = c.holder_html()
    assert "<script>" not in markup and markup.count("<div") == 1
    assert held(markup)["/x"][0].startswith('"><script>')
