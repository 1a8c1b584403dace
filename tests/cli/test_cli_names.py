"""``models.track.context.short_names``: the names the CLI shows files by."""

from __future__ import annotations

from hypothesis import given
from hypothesis import strategies as st

from models.track.context import short_names


def test_files_of_one_name_are_told_apart_by_their_folders():
    paths = ["/d/MOT17-02/gt/gt.txt", "/d/MOT17-04/gt/gt.txt", "/d/caviar/wk2gt.xml"]
    assert short_names(paths) == {"/d/MOT17-02/gt/gt.txt": "MOT17-02/gt/gt.txt",
                                  "/d/MOT17-04/gt/gt.txt": "MOT17-04/gt/gt.txt",
                                  "/d/caviar/wk2gt.xml": "wk2gt.xml"}  # fmt: skip
    assert short_names(["a/b", "/x/a/b"]) == {"a/b": "a/b", "/x/a/b": "x/a/b"}
    assert short_names(["/a/x.jsonl", "/b/y.jsonl"]) == {"/a/x.jsonl": "x.jsonl",
                                                          "/b/y.jsonl": "y.jsonl"}  # fmt: skip
    assert short_names([]) == {}


@given(st.lists(st.lists(st.sampled_from("abc"), min_size=1, max_size=4), min_size=1,
                max_size=6, unique_by=tuple))
def test_the_names_are_distinct_tails_as_short_as_can_be(parts):
    paths = ["/" + "/".join(p) for p in parts]
    names = short_names(paths)
    assert len(set(names.values())) == len(paths)
    for p, name in names.items():
        assert p == name or p.endswith("/" + name)
        shorter = name.split("/")[1:]  # one part fewer is another path's tail too
        if shorter and p != name:
            assert any(o != p and o.split("/")[-len(shorter):] == shorter for o in paths)
