"""A replay page for a recorded run: one self-contained HTML file, opened in any browser, no server.

``ReplayRecorder`` watches a running tree once per tick (statuses, feedback messages, blackboard
values, each at the world time it changed) and collects the top-camera images the run takes;
``write(path)`` turns them into ``replay.html``: the tree with each node's status at a moment of
world time, a slider over the run, the feedback messages, the blackboard values at that moment
and the camera images, all inline (JavaScript, CSS, images as data URIs), nothing fetched.

The page selects its moment from the address: ``replay.html#t=12.5`` shows the run at 12.5 s of
world time (the last change at or before it), ``#moment=7`` the eighth moment. It writes any
script error into its ``#errors`` element, so a headless browser's dumped DOM shows them.
``dump_dom`` and ``screenshot`` drive a headless Chromium for tests and for the docs picture.
"""

from __future__ import annotations

import base64
import dataclasses
import html
import json
import os
import re
import shutil
import subprocess
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import py_trees
from py_trees.common import Status

from bt_arrange import files
from bt_arrange.errors import BtArrangeError
from bt_arrange.numbers import fixed
from bt_arrange.xmltree.registry import type_label

#: Names under which Debian, Ubuntu and Google ship a Chromium-based browser.
CHROMIUM_NAMES = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable")
#: Wall time [s] a headless browser may take to load the page before it counts as stuck.
BROWSER_TIMEOUT_S = 120.0


def _preorder(root: py_trees.behaviour.Behaviour) -> Iterator[tuple[py_trees.behaviour.Behaviour, int, int]]:
    """``(node, depth, parent index)`` top-down, the order the page draws the tree in."""
    order: list[tuple[py_trees.behaviour.Behaviour, int, int]] = []

    def walk(node: py_trees.behaviour.Behaviour, depth: int, parent: int) -> None:
        index = len(order)
        order.append((node, depth, parent))
        for child in node.children:
            walk(child, depth + 1, index)

    walk(root, 0, -1)
    yield from order


def format_value(value: Any) -> str:
    """A blackboard value as short text: floats to 4 decimals, dataclasses by field, arrays rounded."""
    if isinstance(value, bool) or value is None:
        return str(value)
    if isinstance(value, float):
        return fixed(value, 4)
    if isinstance(value, (tuple, list)):
        inner = ", ".join(format_value(v) for v in value)
        return f"({inner})" if isinstance(value, tuple) else f"[{inner}]"
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        fields = ", ".join(f"{f.name}={format_value(getattr(value, f.name))}" for f in dataclasses.fields(value))
        return f"{type(value).__name__}({fields})"
    if hasattr(value, "tolist"):  # numpy arrays and scalars
        return format_value(value.tolist())
    return str(value)


#: A table cell's text longer than this is summarised (``4 values``, a type's name).
CELL_CHARS = 40


def _cell(value: Any) -> str:
    text = format_value(value)
    if len(text) <= CELL_CHARS:
        return text
    name = getattr(value, "name", None)
    if isinstance(name, str):
        return name
    if isinstance(value, (tuple, list)) or hasattr(value, "__len__"):
        return f"{len(value)} values"
    return type(value).__name__


def table_of(value: Any) -> dict[str, Any] | None:
    """A sequence of records of one type (a puzzle's pieces, its solved targets) as a table, else None.

    ``{"columns": [field names], "rows": [[cell texts]]}``; a long field is summarised (``CELL_CHARS``).
    """
    if not isinstance(value, (tuple, list)) or not value:
        return None
    first = value[0]
    if not dataclasses.is_dataclass(first) or isinstance(first, type):
        return None
    if any(type(item) is not type(first) for item in value):
        return None
    columns = [f.name for f in dataclasses.fields(first)]
    rows = [[_cell(getattr(item, column)) for column in columns] for item in value]
    return {"columns": columns, "rows": rows}


@dataclass
class ReplayRecorder:
    """Collects what the replay page shows while a tree runs; ``observe(time_s)`` after every tick."""

    root: py_trees.behaviour.Behaviour
    nodes: list[dict[str, Any]] = field(init=False)
    events: list[dict[str, Any]] = field(init=False, default_factory=list)
    blackboard: list[dict[str, Any]] = field(init=False, default_factory=list)
    images: list[dict[str, Any]] = field(init=False, default_factory=list)

    def __post_init__(self) -> None:
        self._behaviours: list[py_trees.behaviour.Behaviour] = []
        self._index_of: dict[Any, int] = {}
        self._child_counts: list[int] = []
        self.nodes = []
        self._status: list[Status] = []
        self._feedback: list[str] = []
        self._values: dict[str, tuple[Any, str]] = {}
        self._grow(0.0)

    def _grow(self, time_s: float) -> None:
        """Take in the nodes built since the last look (a solved puzzle's pieces), born at ``time_s``.

        A node keeps its index for the whole run (the events refer to it); ``write`` puts them in
        the tree's order at the end.
        """
        order = list(_preorder(self.root))
        for node, depth, parent in order:
            if node.id in self._index_of:
                self._child_counts[self._index_of[node.id]] = len(node.children)
                continue
            parent_index = -1 if parent < 0 else self._index_of[order[parent][0].id]
            self._index_of[node.id] = len(self._behaviours)
            self._behaviours.append(node)
            self._child_counts.append(len(node.children))
            self.nodes.append(
                {"name": node.name, "kind": type_label(node), "depth": depth, "parent": parent_index, "born": time_s}
            )
            self._status.append(Status.INVALID)
            self._feedback.append("")

    def observe(self, time_s: float) -> None:
        """Note every status, feedback message and blackboard value that changed since the last look."""
        time_s = round(time_s, 4)
        if any(len(node.children) != count for node, count in zip(self._behaviours, self._child_counts, strict=True)):
            self._grow(time_s)
        for index, node in enumerate(self._behaviours):
            if node.status != self._status[index] or node.feedback_message != self._feedback[index]:
                self._status[index] = node.status
                self._feedback[index] = node.feedback_message
                self.events.append(
                    {"t": time_s, "node": index, "status": node.status.value, "feedback": node.feedback_message}
                )
        for key, value in py_trees.blackboard.Blackboard.storage.items():
            last = self._values.get(key)
            if last is not None and last[0] is value:
                continue
            text = format_value(value)
            if last is None or last[1] != text:
                entry: dict[str, Any] = {"t": time_s, "key": key, "value": text}
                rows = table_of(value)
                if rows is not None:
                    entry["table"] = rows
                self.blackboard.append(entry)
            self._values[key] = (value, text)

    def add_image(self, time_s: float, label: str, path: Path | str, data: bytes | None = None) -> None:
        """A camera image saved at ``time_s`` of world time (embedded when the page is written).

        ``data`` is the PNG itself, when the caller has it: the page then does not read ``path``
        (which a full disk may have kept from being written).
        """
        self.images.append({"t": round(time_s, 4), "label": label, "path": str(path), "data": data})

    def moments(self) -> list[float]:
        """The world times the slider stops at: every time something the page shows changed."""
        times = (
            {0.0} | {e["t"] for e in self.events} | {b["t"] for b in self.blackboard} | {i["t"] for i in self.images}
        )
        return sorted(times)

    def write(self, path: Path | str, *, title: str, summary: dict[str, Any] | None = None) -> Path:
        """Write the self-contained page to ``path``."""
        path = Path(path)
        images = []
        for image in self.images:
            png = image.get("data")
            data = base64.b64encode(png if png is not None else Path(image["path"]).read_bytes()).decode("ascii")
            images.append({"t": image["t"], "label": image["label"], "src": f"data:image/png;base64,{data}"})
        # The nodes in the tree's order at the end (those built while it ran under their parent),
        # the events renumbered to match.
        order = [self._index_of[node.id] for node, _, _ in _preorder(self.root) if node.id in self._index_of]
        shown = set(order)
        order += [index for index in range(len(self.nodes)) if index not in shown]
        position = {old: new for new, old in enumerate(order)}
        nodes = [{**self.nodes[old], "parent": position.get(self.nodes[old]["parent"], -1)} for old in order]
        events = [{**event, "node": position[event["node"]]} for event in self.events]
        payload = {
            "title": title,
            "summary": summary or {},
            "nodes": nodes,
            "events": events,
            "blackboard": self.blackboard,
            "images": images,
            "moments": self.moments(),
        }
        # Every "<" of the data as "\u003c" (JSON's own escape): no "</script>" or "<!--" can end or
        # change the <script> element, whatever a name or a feedback message holds.
        data = json.dumps(payload, allow_nan=False).replace("<", "\\u003c")
        # One pass over the page's markers: a value inserted is never searched for another marker
        # (a tree named "__DATA__" stays its name).
        values = {"__TITLE__": _html_escape(title), "__DATA__": data}
        page = re.sub("__TITLE__|__DATA__", lambda match: values[match.group(0)], _PAGE)
        path.parent.mkdir(parents=True, exist_ok=True)
        return files.write_text(path, page)  # whole or not at all: never a page cut short


def _html_escape(text: str) -> str:
    return html.escape(text, quote=True)


def status_at(transitions: list[dict[str, Any]], time_s: float) -> dict[str, str]:
    """Each behaviour's status at ``time_s`` from a transition log (``transitions.jsonl`` lines)."""
    statuses: dict[str, str] = {}
    for transition in transitions:
        if transition["time_s"] <= time_s + 1e-9:
            statuses[transition["behaviour"]] = transition["new"]
    return statuses


# ----------------------------------------------------------------------------------------------
# A headless Chromium, for tests and for the docs' screenshot
# ----------------------------------------------------------------------------------------------


def find_chromium() -> str | None:
    """The path of a Chromium-based browser, or None when none is installed."""
    for name in CHROMIUM_NAMES:
        found = shutil.which(name)
        if found:
            return found
    return None


def _chromium(page: Path, fragment: str, *options: str) -> subprocess.CompletedProcess[str]:
    browser = find_chromium()
    if browser is None:
        raise BtArrangeError(
            f"no headless browser: install Chromium (apt-get install chromium); looked for {CHROMIUM_NAMES}"
        )
    command = [browser, "--headless", "--disable-gpu", "--hide-scrollbars", "--no-first-run", *options]
    if hasattr(os, "geteuid") and os.geteuid() == 0:
        command.append("--no-sandbox")  # Chromium refuses to run as root with its sandbox
    url = Path(page).resolve().as_uri() + (f"#{fragment}" if fragment else "")
    try:
        return subprocess.run([*command, url], capture_output=True, text=True, timeout=BROWSER_TIMEOUT_S, check=True)
    except subprocess.TimeoutExpired as error:
        raise BtArrangeError(f"{browser} did not load {url} within {BROWSER_TIMEOUT_S:g} s") from error
    except subprocess.CalledProcessError as error:
        last = (error.stderr or "").strip().splitlines()[-1:] or ["no message"]
        raise BtArrangeError(f"{browser} failed on {url} (exit {error.returncode}): {last[0]}") from error


def dump_dom(page: Path | str, fragment: str = "") -> str:
    """The page's DOM after its scripts ran, as a headless Chromium serialises it."""
    return _chromium(Path(page), fragment, "--dump-dom").stdout


def screenshot(page: Path | str, out: Path | str, fragment: str = "", size: tuple[int, int] = (1400, 900)) -> Path:
    """A PNG of the page (``size`` in CSS pixels) at the moment ``fragment`` selects."""
    out = Path(out).resolve()
    out.parent.mkdir(parents=True, exist_ok=True)
    _chromium(Path(page), fragment, f"--screenshot={out}", f"--window-size={size[0]},{size[1]}")
    if not out.is_file():
        raise BtArrangeError(f"the browser wrote no screenshot to {out}")
    return out


_PAGE = r"""<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<title>__TITLE__ - bt-arrange replay</title>
<style>
  body { font: 14px/1.35 system-ui, sans-serif; margin: 0; color: #222; background: #fafafa; }
  table.records { border-collapse: collapse; font-size: 12px; }
  table.records th, table.records td { border: 1px solid #ddd; padding: 1px 4px; }
  header { position: sticky; top: 0; background: #fff; border-bottom: 1px solid #ddd; padding: 8px 14px; z-index: 1; }
  header h1 { font-size: 17px; margin: 0 0 4px 0; }
  #controls { display: flex; gap: 10px; align-items: center; }
  #slider { flex: 1; }
  #time { font-variant-numeric: tabular-nums; min-width: 15em; }
  main { display: grid; grid-template-columns: minmax(420px, 1fr) minmax(380px, 640px); gap: 14px; padding: 10px 14px; }
  section h2 { font-size: 14px; margin: 10px 0 4px 0; color: #555; }
  .node { white-space: nowrap; padding: 1px 4px; border-radius: 3px; }
  .node .status { display: inline-block; width: 5.8em; font-size: 11px; text-align: center; border-radius: 3px;
                  margin-right: 6px; color: #fff; background: #bbb; }
  .node[data-status="RUNNING"] .status { background: #1f6fd0; }
  .node[data-status="SUCCESS"] .status { background: #2a9d4b; }
  .node[data-status="FAILURE"] .status { background: #d1342f; }
  .node[data-status="INVALID"] { color: #888; }
  .node.changed { background: #fff3bf; }
  .node .kind { color: #888; font-size: 12px; margin-left: 4px; }
  .node .feedback { color: #555; font-style: italic; margin-left: 8px; white-space: normal; }
  #camera { width: 100%; border: 1px solid #ccc; background: #000; min-height: 60px; }
  #thumbs { display: flex; flex-wrap: wrap; gap: 4px; }
  #thumbs img { width: 92px; border: 2px solid transparent; cursor: pointer; }
  #thumbs img.current { border-color: #1f6fd0; }
  table { border-collapse: collapse; width: 100%; font-size: 12px; }
  td, th { border-bottom: 1px solid #eee; padding: 2px 4px; text-align: left; vertical-align: top; }
  td.value { font-family: ui-monospace, monospace; word-break: break-all; }
  tr.changed { background: #fff3bf; }
  #log { font-size: 12px; font-family: ui-monospace, monospace; max-height: 220px; overflow-y: auto; }
  #errors:empty { display: none; }
  #errors { color: #fff; background: #b00020; padding: 6px; margin: 0; }
</style>
</head>
<body>
<pre id="errors"></pre>
<script>
  // First of all: any script error of this page is written into #errors, where a person and a
  // headless browser's dumped DOM both see it.
  (function () {
    var box = document.getElementById("errors");
    function report(text) { box.textContent += text + "\n"; }
    window.addEventListener("error", function (e) { report("error: " + e.message + " (line " + e.lineno + ")"); });
    window.addEventListener("unhandledrejection", function (e) { report("unhandled rejection: " + e.reason); });
    var consoleError = console.error;
    console.error = function () {
      report("console.error: " + Array.prototype.join.call(arguments, " "));
      consoleError.apply(console, arguments);
    };
  })();
</script>
<header>
  <h1 id="title">__TITLE__</h1>
  <div id="summary"></div>
  <div id="controls">
    <button id="previous" title="previous moment">&#9664;</button>
    <button id="play" title="play / pause">play</button>
    <button id="next" title="next moment">&#9654;</button>
    <input id="slider" type="range" min="0" max="0" value="0" step="1" aria-label="moment of the run">
    <span id="time"></span>
  </div>
</header>
<main>
  <section>
    <h2>Tree: status and feedback at this moment (changed at this moment: highlighted)</h2>
    <div id="tree"></div>
    <h2>Changes up to this moment (latest first)</h2>
    <div id="log"></div>
  </section>
  <section>
    <h2>Top camera: <span id="camera-label">no image yet</span></h2>
    <img id="camera" alt="top camera image">
    <div id="thumbs"></div>
    <h2>Blackboard at this moment</h2>
    <table><thead><tr><th>key</th><th>value</th><th>since (s)</th></tr></thead><tbody id="blackboard"></tbody></table>
  </section>
</main>
<script id="replay-data" type="application/json">__DATA__</script>
<script>
(function () {
  "use strict";
  var data = JSON.parse(document.getElementById("replay-data").textContent);
  var moments = data.moments;
  var slider = document.getElementById("slider");
  var rows = [];

  function el(tag, cls, text) {
    var e = document.createElement(tag);
    if (cls) e.className = cls;
    if (text !== undefined) e.textContent = text;
    return e;
  }

  // The tree, drawn once; each moment only updates statuses and feedback.
  var tree = document.getElementById("tree");
  data.nodes.forEach(function (node, index) {
    var row = el("div", "node");
    row.dataset.index = String(index);
    row.dataset.name = node.name;
    row.style.paddingLeft = (4 + 18 * node.depth) + "px";
    row.appendChild(el("span", "status", "INVALID"));
    row.appendChild(el("span", "name", node.name));
    row.appendChild(el("span", "kind", node.kind));
    row.appendChild(el("span", "feedback", ""));
    tree.appendChild(row);
    rows.push(row);
  });

  // The verdict is the parts': how many are within, and each that is not with its offset and why.
  // The tree's own status is shown only for a tree without parts.
  var summary = data.summary || {};
  var parts = [];
  var objects = summary.objects || [];
  if (objects.length) {
    var within = objects.filter(function (o) { return o.status === "within"; }).length;
    var known = summary.threshold_mm !== undefined && summary.threshold_mm !== null;
    var limit = known ? " " + summary.threshold_mm + " mm" : "";
    parts.push(within + " of " + objects.length + " within" + limit);
  } else if (summary.tree_status) {
    parts.push("ended " + summary.tree_status);
  }
  if (summary.sim_seconds !== undefined) parts.push(summary.sim_seconds.toFixed(1) + " s of world time");
  objects.forEach(function (o) {
    var offset = o.final_offset_mm === null ? "" : " " + o.final_offset_mm.toFixed(2) + " mm";
    var reason = o.status !== "within" && o.reason ? " (" + o.reason + ")" : "";
    parts.push(o.name + ": " + o.status + offset + reason);
  });
  document.getElementById("summary").textContent = parts.join(" | ");

  var thumbs = document.getElementById("thumbs");
  var thumbImages = data.images.map(function (image, index) {
    var img = el("img");
    img.src = image.src;
    img.alt = image.label;
    img.title = image.label + " at " + image.t.toFixed(2) + " s";
    img.addEventListener("click", function () { select(momentAt(image.t)); });
    thumbs.appendChild(img);
    return img;
  });

  slider.max = String(moments.length - 1);

  function momentAt(timeS) {
    // The last moment at or before timeS (statuses hold until the next change).
    var lo = 0, hi = moments.length - 1;
    if (timeS < moments[0]) return 0;
    while (lo < hi) {
      var mid = Math.ceil((lo + hi) / 2);
      if (moments[mid] <= timeS + 1e-9) lo = mid; else hi = mid - 1;
    }
    return lo;
  }

  function recordTable(table) {
    var box = el("table", "records");
    var head = el("tr");
    table.columns.forEach(function (c) { head.appendChild(el("th", "", c)); });
    box.appendChild(head);
    table.rows.forEach(function (cells) {
      var tr = el("tr");
      cells.forEach(function (c) { tr.appendChild(el("td", "", c)); });
      box.appendChild(tr);
    });
    return box;
  }

  function render(index) {
    var t = moments[index];
    var status = data.nodes.map(function () { return "INVALID"; });
    var feedback = data.nodes.map(function () { return ""; });
    var changed = {};
    var log = [];
    data.events.forEach(function (e) {
      if (e.t > t + 1e-9) return;
      status[e.node] = e.status;
      feedback[e.node] = e.feedback;
      if (e.t === t) changed[e.node] = true;
      log.push(e);
    });
    rows.forEach(function (row, i) {
      row.hidden = (data.nodes[i].born || 0) > t + 1e-9;  // built later in the run (a solved puzzle's pieces)
      row.dataset.status = status[i];
      row.children[0].textContent = status[i];
      row.children[3].textContent = feedback[i];
      row.classList.toggle("changed", !!changed[i]);
    });

    var values = {}, since = {}, tables = {};
    data.blackboard.forEach(function (b) {
      if (b.t > t + 1e-9) return;
      values[b.key] = b.value;
      tables[b.key] = b.table || null;
      since[b.key] = b.t;
    });
    var body = document.getElementById("blackboard");
    body.textContent = "";
    Object.keys(values).sort().forEach(function (key) {
      var tr = el("tr", since[key] === t ? "changed" : "");
      tr.dataset.key = key;
      tr.appendChild(el("td", "key", key));
      var cell = el("td", "value", tables[key] ? "" : values[key]);
      if (tables[key]) cell.appendChild(recordTable(tables[key]));
      tr.appendChild(cell);
      tr.appendChild(el("td", "since", since[key].toFixed(2)));
      body.appendChild(tr);
    });

    var shown = -1;
    data.images.forEach(function (image, i) { if (image.t <= t + 1e-9) shown = i; });
    var camera = document.getElementById("camera");
    if (shown >= 0) {
      camera.src = data.images[shown].src;
      document.getElementById("camera-label").textContent =
        data.images[shown].label + " (taken at " + data.images[shown].t.toFixed(2) + " s)";
    } else {
      camera.removeAttribute("src");
      document.getElementById("camera-label").textContent = "no image yet";
    }
    thumbImages.forEach(function (img, i) { img.classList.toggle("current", i === shown); });

    var logBox = document.getElementById("log");
    logBox.textContent = "";
    log.slice(-40).reverse().forEach(function (e) {
      var line = e.t.toFixed(2) + " s  " + data.nodes[e.node].name + "  " + e.status;
      if (e.feedback) line += "  " + e.feedback;
      logBox.appendChild(el("div", e.t === t ? "changed" : "", line));
    });

    document.getElementById("time").textContent =
      "t = " + t.toFixed(3) + " s (moment " + (index + 1) + " of " + moments.length + ")";
    document.body.dataset.moment = String(index);
    document.body.dataset.time = String(t);
  }

  function select(index) {
    slider.value = String(index);
    slider.dispatchEvent(new Event("input"));
  }

  slider.addEventListener("input", function () { render(Number(slider.value)); });
  function step(by) { select(Math.max(0, Math.min(moments.length - 1, Number(slider.value) + by))); }
  document.getElementById("previous").addEventListener("click", function () { step(-1); });
  document.getElementById("next").addEventListener("click", function () { step(1); });
  var timer = null;
  var play = document.getElementById("play");
  function pause() { clearInterval(timer); timer = null; play.textContent = "play"; }
  play.addEventListener("click", function () {
    if (timer !== null) { pause(); return; }
    play.textContent = "pause";
    timer = setInterval(function () {
      if (Number(slider.value) + 1 >= moments.length) { pause(); return; }
      step(1);
    }, 120);
  });

  function fromAddress() {
    var hash = window.location.hash.replace(/^#/, "");
    var params = new URLSearchParams(hash);
    if (params.has("t")) return momentAt(Number(params.get("t")));
    if (params.has("moment")) return Math.max(0, Math.min(moments.length - 1, Number(params.get("moment"))));
    return moments.length - 1;
  }
  window.addEventListener("hashchange", function () { select(fromAddress()); });
  select(fromAddress());
  document.body.dataset.ready = "1";
})();
</script>
</body>
</html>
"""
