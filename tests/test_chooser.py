"""The Fig. 9-1 chooser: a decision tree in a data file, walked by answer numbers."""

from __future__ import annotations

import pytest

from shoal.app.lessons import LessonError
from shoal.app.lessons.chooser import Leaf, Question, parse_tree, paths, shipped_tree, trail, walk
from shoal.app.lessons.scenes import load_scene
from shoal.app.limits import check_app_limits
from shoal.app.tab import kind_for

TREE = shipped_tree()

SMALL = '''
title = "t"
start = "a"
[questions.a]
question = "A?"
answers = [{ label = "yes", next = "b" }, { label = "no", next = "leaf-2" }]
[questions.b]
question = "B?"
answers = [{ label = "yes", next = "leaf-1" }, { label = "no", next = "leaf-2" }]
[leaves.leaf-1]
title = "one"
chapter = "4"
why = "because"
preset = "course-dvc"
[leaves.leaf-2]
title = "two"
chapter = "5"
why = "because"
preset = "course-nonomni"
'''


def test_walking_answers_reaches_questions_and_leaves():
    tree = parse_tree(SMALL)
    assert isinstance(walk(tree, []), Question) and walk(tree, []).question == "A?"
    assert walk(tree, [0]).question == "B?"
    assert walk(tree, [0, 0]).title == "one"
    assert walk(tree, [1]).title == walk(tree, [0, 1]).title == "two"  # two paths to one leaf
    assert paths(tree) == {"leaf-1": [[0, 0]], "leaf-2": [[1], [0, 1]]}
    assert trail(tree, [0, 1]) == ["yes", "no"]
    with pytest.raises(IndexError, match="answer 1: the question has 2 answers"):
        walk(tree, [2])
    with pytest.raises(IndexError, match="answer 2: the path already reached a leaf"):
        walk(tree, [1, 0])


@pytest.mark.parametrize(
    "old, new, expected",
    [
        ('next = "leaf-2" }]\n[questions.b]', 'next = "nowhere" }]\n[questions.b]',
         "questions.a.answers.1: next = 'nowhere' is neither a question nor a leaf"),
        ('start = "a"', 'start = "b"', "a: no answer leads there"),
        ('start = "a"', 'start = "leaf-1"', "start: no question named 'leaf-1'"),
        ('{ label = "yes", next = "leaf-1" }', '{ label = "yes", next = "a" }', "the answers lead back to it"),
        ('answers = [{ label = "yes", next = "leaf-1" }, { label = "no", next = "leaf-2" }]',
         'answers = [{ label = "yes", next = "leaf-1" }]', "questions.b.answers: List should have at least 2"),
        ('preset = "course-dvc"', 'preset = "/etc/passwd"', "leaves.leaf-1.preset: String should match pattern"),
        ('why = "because"\npreset = "course-dvc"', 'preset = "course-dvc"', "leaves.leaf-1.why: Field required"),
        ('title = "t"', 'title = ', "chooser.toml: TOML syntax"),
    ],
)
def test_a_bad_tree_is_refused_with_where(old, new, expected):
    assert old in SMALL
    with pytest.raises(LessonError) as err:
        parse_tree(SMALL.replace(old, new, 1))
    assert any(expected in m for m in err.value.messages), err.value.messages


def test_the_shipped_chooser_reaches_every_leaf():
    reached = paths(TREE)
    assert all(reached[name] for name in TREE.leaves), {k: v for k, v in reached.items() if not v}
    for name, leaf_paths in reached.items():
        for path in leaf_paths:
            assert walk(TREE, path) == TREE.leaves[name]
    # Fig. 9-1's distinctions: the motion of the robots, the kind of source, the band, the task
    presets = {leaf.preset for leaf in TREE.leaves.values()}
    assert {"course-dvc", "course-nonomni", "sonar-xb-pso", "sonar-x-pso", "sonar-gt-pso",
            "escort-stationary", "escort-moving"} <= presets


@pytest.mark.parametrize("name", sorted(TREE.leaves))
def test_every_leaf_opens_a_scene_the_app_can_show(name):
    leaf = TREE.leaves[name]
    scenario = check_app_limits(load_scene(leaf.preset, dict(leaf.values)))
    kind_for(scenario)
    assert isinstance(leaf, Leaf) and leaf.why
