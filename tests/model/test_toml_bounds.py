"""The bounded TOML loader of scenes and profiles: nesting counted outside strings and comments, refused past
its limit before the parser recurses, accepted up to it."""

import pytest

from vibkit.model.scene import MAX_TOML_DEPTH, SceneError, toml_loads


def _nested(depth):
    return "x = " + "[" * depth + "1" + "]" * depth + "\n"


def test_nesting_up_to_the_limit_is_parsed():
    data = toml_loads(_nested(MAX_TOML_DEPTH), "s.toml")
    v, depth = data["x"], 0
    while isinstance(v, list):
        v, depth = v[0], depth + 1
    assert (v, depth) == (1, MAX_TOML_DEPTH)


@pytest.mark.parametrize("depth", [MAX_TOML_DEPTH + 1, 10_000])
def test_nesting_past_the_limit_is_refused_naming_the_file(depth):
    with pytest.raises(SceneError, match=rf"^s\.toml: arrays or tables nested more than {MAX_TOML_DEPTH} deep"):
        toml_loads(_nested(depth), "s.toml")


def test_inline_tables_count_as_nesting():
    text = "x = " + "{a = " * (MAX_TOML_DEPTH + 1) + "1" + "}" * (MAX_TOML_DEPTH + 1) + "\n"
    with pytest.raises(SceneError, match="nested more than"):
        toml_loads(text, "s.toml")


def test_brackets_in_strings_and_comments_are_not_nesting():
    many = "[" * (3 * MAX_TOML_DEPTH)
    text = (
        f'a = "{many}"  # {many}\n'
        f"b = '{many}'\n"
        f'c = """\n{many}\n"""\n'
        f"d = '''{many}'''\n"
        f'e = "quote \\" {many}"\n'
        "f = [[1, 2], [3]]\n"
    )
    data = toml_loads(text, "s.toml")
    assert data["a"] == data["b"] == data["d"] == many
    assert data["c"] == many + "\n" and data["e"] == f'quote " {many}'
    assert data["f"] == [[1, 2], [3]]
