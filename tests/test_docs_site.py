"""The documentation site: built as the README says, complete, and working in a browser.

``mkdocs build --strict`` (mkdocs.yml at the root) must pass: any warning (a broken link or anchor, a page
left out of the navigation, a docstring mkdocstrings cannot render) fails it. The site must hold every
guide of docs/ and a page for every public module, with the backends' classes on theirs.

Then a real headless Chromium opens it, served over HTTP on 127.0.0.1 (the search runs in a web
worker, which a ``file://`` page may not start), driven through the Chrome DevTools protocol: the home
page and one API page load with no JavaScript error and nothing fetched from another address, a search
typed into the search box lists the page that documents the word, and a click in the navigation opens
the page it names. Without Chromium, or without the docs extra, those tests skip and say why.
"""

from __future__ import annotations

import contextlib
import functools
import http.server
import importlib.util
import json
import os
import re
import shutil
import subprocess
import sys
import threading
import time
import urllib.request
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from docblocks import ROOT

from bt_arrange import replay

MISSING = [
    name
    for name in ("mkdocs", "material", "mkdocstrings", "mkdocstrings_handlers")
    if importlib.util.find_spec(name) is None
]
pytestmark = pytest.mark.skipif(
    bool(MISSING),
    reason=f"no {', '.join(MISSING)}: pip install -e '.[docs]' (the test extra has them) to build the site",
)
BROWSER_WAIT_S = 30.0


@pytest.fixture(scope="module")
def site(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The site, built by the README's command (into a temporary folder instead of site/)."""
    out = tmp_path_factory.mktemp("site")
    env = dict(os.environ, NO_MKDOCS_2_WARNING="1")
    done = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(out)],
        cwd=ROOT, env=env, capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    log = done.stdout + done.stderr
    assert done.returncode == 0, log[-4000:]
    warnings = [line for line in log.split("\n") if line.startswith(("WARNING", "ERROR"))]
    assert warnings == [], "\n".join(warnings)
    return out


def test_the_readme_names_the_build_command() -> None:
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    assert "mkdocs build --strict" in readme
    assert (ROOT / "mkdocs.yml").is_file()


def test_every_guide_is_a_page_and_the_readme_is_the_home_page(site: Path) -> None:
    for guide in sorted((ROOT / "docs").glob("*.md")):
        assert (site / guide.with_suffix(".html").name).is_file(), guide.name
    home = (site / "index.html").read_text(encoding="utf-8")
    assert "Behaviour trees for precise robotic arrangement" in home
    assert 'href="cli.html#the-replay-page"' in home, "the README's links into docs/ point at the site's pages"
    assert (site / "images" / "replay.png").is_file()


def test_lists_nested_as_github_nests_them_are_nested_on_the_site(site: Path) -> None:
    """docs/ indents a list item's content by 2 (GitHub's reading); Python-Markdown needs 4: the hook re-indents."""
    irregular = (site / "irregular.html").read_text(encoding="utf-8")
    check = irregular.index("<strong>The plan check</strong>")
    assert irregular.index("<ul>", check) < irregular.index("</li>", check), "the plan check's refusals nest"
    experiments = (site / "experiments.html").read_text(encoding="utf-8")
    assert re.search(r'one of:</p>\s*<ul>\s*<li><code>("|&quot;)turn', experiments), "a list in a list item"


def test_every_public_module_has_its_api_page(site: Path) -> None:
    sys.path.insert(0, str(ROOT / "scripts"))  # the site's own list of modules (scripts/ is not a package)
    try:
        import mkdocs_hooks
    finally:
        sys.path.remove(str(ROOT / "scripts"))
    modules = mkdocs_hooks.public_modules()
    assert len(modules["bt_arrange"]) > 80 and len(modules["bt_arrange_sim"]) > 30
    assert "bt_arrange.cli_common" in modules["bt_arrange"] and not any("._" in n for n in modules["bt_arrange"])
    for names in modules.values():
        for name in names:
            page = site / "api" / f"{name}.html"
            assert page.is_file(), name
            assert f'id="{name}"' in page.read_text(encoding="utf-8"), f"{name}: the module's own heading"


@pytest.mark.parametrize(
    "page, names",
    [
        ("bt_arrange_sim.pybullet.backend", ["SimBackend"]),
        ("bt_arrange_sim.mujoco.backend", ["MujocoBackend"]),
        ("bt_arrange_sim.pybullet.cell", ["WorkCell"]),
        ("bt_arrange_sim.pybullet.runs", ["SimulatedRun", "SimWorld"]),
        ("bt_arrange.decorators", ["RepeatUntilWithin"]),
        ("bt_arrange.perception.detection", ["PartDetector", "PartDetector.detect"]),
    ],
)
def test_the_public_classes_are_documented(site: Path, page: str, names: list[str]) -> None:
    text = (site / "api" / f"{page}.html").read_text(encoding="utf-8")
    for name in names:
        assert f'id="{page}.{name}"' in text, f"{page}.{name}"
    assert ":class:`" not in text and "::</p>" not in text, "reStructuredText habits rendered as Markdown"


def test_a_package_s_page_links_its_exports_to_where_they_are_documented(site: Path) -> None:
    text = (site / "api" / "bt_arrange.perception.html").read_text(encoding="utf-8")
    assert 'href="bt_arrange.perception.detection.html#bt_arrange.perception.detection.PartDetector"' in text
    assert 'href="bt_arrange.perception.colours.html"' in text, "its modules are listed"
    assert 'id="bt_arrange.perception.PartDetector"' not in text, "documented once, on its module's page"


# ----------------------------------------------------------------------------------------------
# In a browser
# ----------------------------------------------------------------------------------------------


class _Quiet(http.server.SimpleHTTPRequestHandler):
    def log_message(self, format: str, *args: Any) -> None:  # noqa: A002  (the base class's name)
        pass


class DevTools:
    """One page of a headless Chromium, driven over the DevTools protocol's WebSocket."""

    def __init__(self, url: str) -> None:
        from websockets.sync.client import connect

        self._stack = contextlib.ExitStack()
        self.socket = self._stack.enter_context(connect(url, max_size=None, open_timeout=BROWSER_WAIT_S))
        self.events: list[dict[str, Any]] = []
        self._id = 0

    def call(self, method: str, **params: Any) -> dict[str, Any]:
        self._id += 1
        self.socket.send(json.dumps({"id": self._id, "method": method, "params": params}))
        while True:
            message = json.loads(self.socket.recv(timeout=BROWSER_WAIT_S))
            if message.get("id") == self._id:
                assert "error" not in message, f"{method}: {message['error']}"
                return message.get("result", {})
            self.events.append(message)

    def evaluate(self, expression: str) -> Any:
        result = self.call("Runtime.evaluate", expression=expression, returnByValue=True, awaitPromise=True)
        assert "exceptionDetails" not in result, result["exceptionDetails"]
        return result["result"].get("value")

    def click(self, selector: str) -> None:
        """Click the first element ``selector`` finds, once this evaluation has returned.

        A click that navigates at once can end the page's context before the evaluation answers
        ("Inspected target navigated or closed"): the click is left to the page's next task.
        """
        found = self.evaluate(
            f"(() => {{ const e = document.querySelector({json.dumps(selector)}); "
            "if (e) setTimeout(() => e.click(), 0); return !!e; })()"
        )
        assert found, f"nothing matches {selector}"

    def wait_for(self, expression: str, what: str) -> Any:
        """Poll ``expression`` until it is truthy (the page's own scripts run meanwhile)."""
        deadline = time.monotonic() + BROWSER_WAIT_S
        while time.monotonic() < deadline:
            try:
                value = self.evaluate(expression)
            except AssertionError as error:
                # Evaluated while a click navigates: the old page's context is gone, the new one not yet there.
                if "navigated or closed" not in str(error) and "context" not in str(error).lower():
                    raise
                value = None
            if value:
                return value
            time.sleep(0.1)
        raise AssertionError(f"{what}: not within {BROWSER_WAIT_S:.0f} s")

    def open(self, url: str) -> None:
        self.call("Page.navigate", url=url)
        self.wait_for("document.readyState === 'complete' && location.href === " + json.dumps(url), f"loading {url}")

    def errors(self) -> list[str]:
        """JavaScript errors, error messages on the console, and failed requests, since the page opened."""
        found = []
        for event in self.events:
            method, params = event.get("method"), event.get("params", {})
            if method == "Runtime.exceptionThrown":
                details = params["exceptionDetails"]
                found.append(details.get("exception", {}).get("description") or details.get("text", "exception"))
            elif method == "Runtime.consoleAPICalled" and params.get("type") in ("error", "assert"):
                found.append(" ".join(str(arg.get("value", arg.get("description", ""))) for arg in params["args"]))
            elif method == "Log.entryAdded" and params["entry"].get("level") == "error":
                found.append(f"{params['entry'].get('text')} {params['entry'].get('url', '')}")
            elif method == "Network.loadingFailed" and not params.get("canceled"):
                found.append(f"request failed: {params.get('errorText')} ({params.get('requestId')})")
        return found

    def requested(self) -> list[str]:
        return [e["params"]["request"]["url"] for e in self.events if e.get("method") == "Network.requestWillBeSent"]

    def heading(self) -> str:
        """The page's title as a reader sees it (without the permalink's mark)."""
        return self.evaluate(
            "(() => { const h = document.querySelector('h1').cloneNode(true);"
            " h.querySelectorAll('.headerlink').forEach(a => a.remove()); return h.textContent.trim(); })()"
        )

    def close(self) -> None:
        self._stack.close()


@pytest.fixture(scope="module")
def browser(site: Path, tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[DevTools, str]]:
    """A headless Chromium on a page, and the address of the site served on 127.0.0.1."""
    chromium = replay.find_chromium()
    if chromium is None:
        pytest.skip(f"no Chromium found ({', '.join(replay.CHROMIUM_NAMES)}): apt-get install chromium")
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), functools.partial(_Quiet, directory=str(site)))
    threading.Thread(target=server.serve_forever, daemon=True).start()
    base = f"http://127.0.0.1:{server.server_address[1]}/"
    profile = tmp_path_factory.mktemp("chromium-profile")
    command = [chromium, "--headless", "--disable-gpu", "--no-first-run", "--no-default-browser-check",
               "--remote-debugging-address=127.0.0.1", "--remote-debugging-port=0", f"--user-data-dir={profile}",
               "--window-size=1280,900", "about:blank"]  # fmt: skip
    if hasattr(os, "geteuid") and os.geteuid() == 0:
        command.append("--no-sandbox")  # Chromium refuses to run as root with its sandbox
    process = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    tools = None
    try:
        port_file = profile / "DevToolsActivePort"
        deadline = time.monotonic() + BROWSER_WAIT_S
        while not (port_file.is_file() and port_file.read_text().strip()) and time.monotonic() < deadline:
            assert process.poll() is None, f"{chromium} exited with {process.returncode}"
            time.sleep(0.1)
        port = int(port_file.read_text().split()[0])
        with urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list", timeout=BROWSER_WAIT_S) as answer:
            page = next(target for target in json.load(answer) if target["type"] == "page")
        tools = DevTools(page["webSocketDebuggerUrl"])
        for domain in ("Page", "Runtime", "Log", "Network"):
            tools.call(f"{domain}.enable")
        yield tools, base
    finally:
        if tools is not None:
            tools.close()
        process.terminate()
        try:
            process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()
        server.shutdown()
        server.server_close()
        shutil.rmtree(profile, ignore_errors=True)


def _no_errors_and_nothing_from_elsewhere(tools: DevTools, base: str) -> None:
    assert tools.errors() == []
    elsewhere = [url for url in tools.requested() if not url.startswith((base, "data:", "blob:", "about:"))]
    assert elsewhere == [], "the site loads nothing from another address"


def test_the_home_page_s_search_box_finds_a_behaviour(browser: tuple[DevTools, str]) -> None:
    tools, base = browser
    tools.events.clear()
    tools.open(base + "index.html")
    assert tools.heading() == "bt-arrange"
    # Focus the search box as a click on it would, and type into it as a keyboard would.
    tools.evaluate("document.querySelector('[data-md-toggle=search]').checked = true")
    tools.evaluate("document.querySelector('input.md-search__input').focus()")
    tools.call("Input.insertText", text="RepeatUntilWithin")
    found = tools.wait_for(
        "Array.from(document.querySelectorAll('.md-search-result__item a')).map(a => a.getAttribute('href'))"
        ".filter(h => h.includes('decorators'))",
        "a search result on the page of bt_arrange.decorators",
    )
    assert any("api/bt_arrange.decorators.html" in href for href in found)
    _no_errors_and_nothing_from_elsewhere(tools, base)


def test_the_navigation_opens_a_guide_and_an_api_page(browser: tuple[DevTools, str]) -> None:
    tools, base = browser
    tools.events.clear()
    tools.open(base + "api/bt_arrange.decorators.html")
    assert tools.heading() == "bt_arrange.decorators"
    assert tools.evaluate("!!document.getElementById('bt_arrange.decorators.RepeatUntilWithin')")
    # The navigation shows where the page is, and a click on a guide's entry opens that guide.
    active = tools.evaluate("document.querySelector('.md-nav__link--active').textContent.trim()")
    assert active == "decorators"
    tools.click(".md-nav__link[href$='trees.html']")
    tools.wait_for("location.pathname.endsWith('/trees.html') && document.readyState === 'complete'", "the guide")
    assert tools.heading() == "Arrangement trees"
    # And from a guide back into the reference: the API overview, then a module by its link.
    tools.click(".md-nav__link[href$='api/index.html']")
    tools.wait_for("location.pathname.endsWith('/api/index.html') && document.readyState === 'complete'", "overview")
    tools.click("article a[href$='bt_arrange_sim.pybullet.backend.html']")
    tools.wait_for("location.pathname.endsWith('/bt_arrange_sim.pybullet.backend.html')", "the backend's page")
    tools.wait_for("document.readyState === 'complete'", "the backend's page loaded")
    assert tools.evaluate("!!document.getElementById('bt_arrange_sim.pybullet.backend.SimBackend')")
    _no_errors_and_nothing_from_elsewhere(tools, base)


def test_a_script_error_would_be_seen(browser: tuple[DevTools, str]) -> None:
    """The error check can fail: an exception thrown in the page is reported."""
    tools, base = browser
    tools.events.clear()
    tools.open(base + "index.html")
    tools.call("Runtime.evaluate", expression="setTimeout(() => undefinedFunction(), 0)")
    tools.wait_for("new Promise(r => setTimeout(() => r(true), 200))", "a moment")
    tools.call("Runtime.evaluate", expression="1")  # read the events that arrived meanwhile
    assert any("undefinedFunction" in error for error in tools.errors())
