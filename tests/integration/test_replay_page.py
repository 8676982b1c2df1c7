"""The replay page of a recorded run, opened in a real headless Chromium.

The page moves its own slider to the moment the address names (``#t=12.5``), as a click would;
the dumped DOM then shows each node's status, which must be the transition log's at that time.
"""

import re
from html.parser import HTMLParser

import cv2
import pytest

from bt_arrange import replay

pytestmark = pytest.mark.skipif(
    replay.find_chromium() is None,
    reason=f"no Chromium found ({', '.join(replay.CHROMIUM_NAMES)}): apt-get install chromium to test the replay page",
)


class PageState(HTMLParser):
    """What the dumped DOM shows: node statuses by name, the error box, the body's data attributes."""

    def __init__(self, dom: str) -> None:
        super().__init__()
        self.statuses: dict[str, str] = {}
        self.names: list[str] = []
        self.body: dict[str, str] = {}
        self.errors = ""
        self._in_errors = False
        self.feed(dom)

    def handle_starttag(self, tag, attrs):
        attributes = dict(attrs)
        if tag == "body":
            self.body = attributes
        if tag == "pre" and attributes.get("id") == "errors":
            self._in_errors = True
        if tag == "div" and "node" in (attributes.get("class") or "").split():
            self.names.append(attributes["data-name"])
            self.statuses[attributes["data-name"]] = attributes["data-status"]

    def handle_endtag(self, tag):
        if tag == "pre":
            self._in_errors = False

    def handle_data(self, data):
        if self._in_errors:
            self.errors += data


def expected_statuses(transitions, time_s, names):
    """Each behaviour's status at ``time_s``, from the transition log alone."""
    statuses = dict.fromkeys(names, "INVALID")
    for transition in transitions:
        if transition["time_s"] <= time_s:
            statuses[transition["behaviour"]] = transition["new"]
    return statuses


def test_the_page_is_one_self_contained_file(four_cubes_xml_record):
    page = (four_cubes_xml_record["dir"] / "replay.html").read_text()
    assert "<link" not in page
    assert not re.search(r"""(src|href)\s*=\s*["'](?!data:|#)""", page), "everything inline"
    assert not re.search(r"https?://", page), "nothing fetched from a network"
    pictures = sorted(p.stem for p in four_cubes_xml_record["dir"].glob("*.png"))
    assert page.count('"src": "data:image/png;base64,') == len(pictures) == 6  # before, 4 after placing, after


def test_the_statuses_shown_at_five_moments_are_the_transition_log_s(four_cubes_xml_record):
    page = four_cubes_xml_record["dir"] / "replay.html"
    transitions = four_cubes_xml_record["transitions"]
    end_s = four_cubes_xml_record["report"]["sim_seconds"]
    shown_moments = []
    for fraction in (0.1, 0.3, 0.5, 0.7, 0.9):
        time_s = round(fraction * end_s, 3)
        state = PageState(replay.dump_dom(page, f"t={time_s}"))
        assert state.errors == "", state.errors
        assert state.body.get("data-ready") == "1", "the page's script ran to its end"
        # 58, and per cube 11 for a stalled correction and 5 that separate touching parts before the pick
        assert len(state.names) == len(set(state.names)) == 122
        assert state.statuses == expected_statuses(transitions, time_s, state.names), f"at {time_s} s"
        assert float(state.body["data-time"]) <= time_s
        shown_moments.append(int(state.body["data-moment"]))
        assert "RUNNING" in state.statuses.values(), "mid-run, something is running"
    assert shown_moments == sorted(set(shown_moments)), "the slider moved forward at each of the five moments"


def test_the_last_moment_shows_the_final_offsets_on_the_blackboard(four_cubes_xml_record):
    dom = replay.dump_dom(four_cubes_xml_record["dir"] / "replay.html")
    state = PageState(dom)
    assert state.statuses["arrangement"] == "SUCCESS"
    for outcome in four_cubes_xml_record["report"]["objects"]:
        row = re.search(rf'<tr[^>]*data-key="/{outcome["name"]}/offset_mm".*?<td class="value">([^<]*)</td>', dom, re.S)
        assert row is not None, outcome["name"]
        assert abs(float(row.group(1)) - outcome["final_offset_mm"]) < 1e-4
    assert "after pushing" in dom, "the last camera image is shown"


def test_a_script_error_would_show_in_the_page(four_cubes_xml_record, tmp_path):
    broken = tmp_path / "broken.html"
    page = (four_cubes_xml_record["dir"] / "replay.html").read_text()
    broken.write_text(page.replace("</body>", "<script>undefinedFunction();</script></body>"))
    state = PageState(replay.dump_dom(broken))
    assert "undefinedFunction" in state.errors


def test_a_screenshot_of_the_page(four_cubes_xml_record, tmp_path):
    out = replay.screenshot(four_cubes_xml_record["dir"] / "replay.html", tmp_path / "replay.png", "t=20")
    picture = cv2.imread(str(out))
    assert picture.shape[:2] == (900, 1400)
    assert picture.std() > 10, "not a blank page"


def test_the_header_counts_the_parts_within_and_names_each_that_is_not(tmp_path):
    import py_trees

    recorder = replay.ReplayRecorder(py_trees.behaviours.Success("arrangement"))
    recorder.observe(0.0)
    summary = {
        "tree_status": "SUCCESS",
        "threshold_mm": 1.0,
        "sim_seconds": 20.0,
        "objects": [
            {"name": "red", "status": "within", "final_offset_mm": 0.2, "reason": ""},
            {"name": "slab 5", "status": "outside", "final_offset_mm": 3.27, "reason": "offset still 3.27 mm"},
        ],
    }
    page = recorder.write(tmp_path / "replay.html", title="t", summary=summary)
    header = re.search(r'<div id="summary">([^<]*)</div>', replay.dump_dom(page)).group(1)
    assert header.startswith("1 of 2 within 1 mm | 20.0 s of world time")
    assert "slab 5: outside 3.27 mm (offset still 3.27 mm)" in header
    assert "SUCCESS" not in header, "the tree's status is never the verdict beside a part outside"
