"""Ports on the nodes: every registered node's XML ports are its class's declaration, built and read back generically.

A node of the project declares ``provided_ports()`` on its class and is registered with one call
(``bt_arrange.xmltree.register_node``); the codecs' errors on bad text are the project's errors.
"""

import inspect
import textwrap

import py_trees
import pytest

from bt_arrange import xmltree
from bt_arrange.errors import BtArrangeError, PortValueError, XmlTreeError
from bt_arrange.ports import COLOURS, DOUBLE, INT, OBJECT_TYPE, OFF_DOUBLE, OFF_STRING, RELEASE, STRING, Port, PortType
from bt_arrange.xmltree import REGISTRY, parse_elements, register_node

OURS = sorted(tag for tag, model in REGISTRY.items() if model.cls.__module__.startswith("bt_arrange."))

#: A text of every port type that is not its default, to build every node with every port set.
SAMPLE_TEXT = {
    "std::string": "red",
    "double": "2.5",
    "int": "7",
    "bool": "true",
    "ObjectType": "bar=outline_mm -40:-20 40:-20 40:20 -40:20 height_mm 40",
    "PlanarPoses": "0.5,0.1,0.0;0.4,0.1,0.0",
    "Release": "y;0.058;0.0;0.01",
    "Directions": "+x,-y",
    "Blockers": "+x=blue;-y=tile 2",
    "Targets": "red,0.5,0.0,0.0;blue,0.5,0.1,0.0",
    "Colours": "teal:rgb:0.0,0.5,0.5",
    "Puzzle": "slab;0.16,0.12,0.02;6;0.002;red;0.5,0,0",
    "BlackboardEntry": "{/elsewhere/entry}",
}
#: Ports whose values are one of a few words.
SAMPLE_PORT_TEXT = {
    "where": "pick",
    "strategy": "learned",
    "opening_m": "0.03",
    "offset_key": "{/red/offset_mm}",
    "corrections_key": "{/red/corrections}",
    "yaw_key": "{/red/yaw_error_deg}",
}


def document(node: str) -> str:
    return f'<root BTCPP_format="4"><BehaviorTree ID="t">{node}</BehaviorTree></root>'


def element(tag: str, attributes: dict[str, str]) -> str:
    """The XML of node ``tag`` with ``attributes``, and the one child a decorator or a control node needs."""
    text = " ".join(f'{name}="{value}"' for name, value in attributes.items())
    children = {"none": "", "one": '<AlwaysSuccess name="c"/>', "many": '<AlwaysSuccess name="c"/>'}
    inner = children[REGISTRY[tag].children]
    return f'<{tag} name="n" {text}>{inner}</{tag}>' if inner else f'<{tag} name="n" {text}/>'


def every_port_set(tag: str) -> dict[str, str]:
    ports = REGISTRY[tag].cls.provided_ports()
    return {port.name: SAMPLE_PORT_TEXT.get(port.name, SAMPLE_TEXT[port.type.name]) for port in ports}


def test_the_project_registers_its_nodes_by_their_classes():
    assert OURS == [
        "ArrangeSolved",
        "Arrangement",
        "CheckStanding",
        "Detect",
        "GraspGuard",
        "Inspect",
        "LookAtHeld",
        "MoveHome",
        "Pick",
        "Place",
        "Push",
        "PushAside",
        "PutBack",
        "Recheck",
        "RepeatUntilWithin",
        "Separate",
        "SolvePuzzle",
        "SurveyPieces",
    ]


@pytest.mark.parametrize("tag", OURS)
def test_a_nodes_xml_ports_are_its_class_declaration(tag):
    """The full TreeNodesModel gives the node the class's ports: names, directions, types, defaults, descriptions.

    A blackboard entry's default is BehaviorTree.CPP's ``{pose}``: the object's own entry.
    """
    model = REGISTRY[tag]
    declared = model.cls.provided_ports()
    assert model.ports == declared
    node = xmltree.from_xml(document(element(tag, every_port_set(tag))))
    written = parse_elements(xmltree.to_xml(node, model="full"))
    (nodes_model,) = [e for e in written.children if e.tag == "TreeNodesModel"]
    (entry,) = [e for e in nodes_model.children if e.attributes["ID"] == tag]
    assert entry.tag == model.category
    ports = [e for e in entry.children if e.tag.endswith("_port")]
    assert [(p.tag, p.attributes["name"], p.attributes["type"], p.attributes.get("default")) for p in ports] == [
        (
            f"{port.direction}_port",
            port.name,
            port.type.name,
            "{" + port.name + "}" if port.entry else None if port.required else port.type.format(port.default),
        )
        for port in declared
    ]
    # The file's own model lists the ports it writes: all of them here, none that it leaves at their defaults.
    compact = parse_elements(xmltree.to_xml(node)).children[-1]
    (used,) = [e for e in compact.children if e.attributes["ID"] == tag]
    assert [p.attributes["name"] for p in used.children] == [p.attributes["name"] for p in ports]
    metadata = [e for e in entry.children if e.tag == "MetadataFields"]
    assert metadata[0].children[0].attributes["description"] == model.cls.node_description


@pytest.mark.parametrize("tag", OURS)
def test_a_nodes_constructor_takes_its_ports_unless_the_class_builds_itself(tag):
    cls = REGISTRY[tag].cls
    if hasattr(cls, "from_ports"):
        # The plan's root (its plan is checked first) and a puzzle's nodes (one port holds the puzzle's whole).
        assert tag in ("Arrangement", "ArrangeSolved", "SolvePuzzle", "SurveyPieces"), "only these build themselves"
        return
    parameters = inspect.signature(cls).parameters
    # A blackboard entry port is not the constructor's: the reader remaps the entry on the node built.
    assert {port.name for port in cls.provided_ports() if not port.entry} <= set(parameters)


@pytest.mark.parametrize("tag", OURS)
def test_every_port_set_builds_the_node_and_reads_back_as_written(tag):
    """The generic build (``cls(name, **values)``) and read-back (``getattr(node, port)``) keep every port's text."""
    given = every_port_set(tag)
    node = xmltree.from_xml(document(element(tag, given)))
    assert type(node) is REGISTRY[tag].cls and node.name == "n"
    written = parse_elements(xmltree.to_xml(node)).children[0].children[0]
    assert written.tag == tag
    assert {name: text for name, text in written.attributes.items() if name != "name"} == given


@pytest.mark.parametrize("tag", OURS)
def test_an_optional_port_left_out_reads_back_as_its_default_and_stays_out(tag):
    """Files written before an optional port existed read, and are written, as they were."""
    model = REGISTRY[tag]
    needed = {port.name for port in model.ports if port.required}
    required = {name: text for name, text in every_port_set(tag).items() if name in needed}
    node = xmltree.from_xml(document(element(tag, required)))
    values = model.ports_of(node)
    for port in model.ports:
        if port.optional:
            assert port.type.format(values[port.name]) == port.type.format(port.default), port.name
    written = parse_elements(xmltree.to_xml(node)).children[0].children[0]
    assert not {port.name for port in model.ports if port.optional} & set(written.attributes)


# ----------------------------------------------------------------------------------------------
# A new behaviour: its class plus one registration
# ----------------------------------------------------------------------------------------------


class Wave(py_trees.behaviour.Behaviour):
    """A behaviour of a user's: wave ``times`` times at ``who``."""

    node_description = "wave at someone"

    @classmethod
    def provided_ports(cls) -> tuple[Port, ...]:
        return (
            Port("who", STRING, description="whom to wave at"),
            Port("times", INT, 1, "how often"),
            Port("pause_s", OFF_DOUBLE, None, "between waves [s] (0: none)", optional=True),
        )

    def __init__(self, name: str, who: str, times: int = 1, pause_s: float | None = None) -> None:
        super().__init__(name)
        self.who, self.times, self.pause_s = who, times, pause_s

    def update(self) -> py_trees.common.Status:
        return py_trees.common.Status.SUCCESS


class Twice(py_trees.decorators.Decorator):
    """A decorator whose constructor differs from its ports: it builds itself and says its values."""

    node_description = "run the child twice"

    @classmethod
    def provided_ports(cls) -> tuple[Port, ...]:
        return (Port("label", OFF_STRING, None, "a label (empty: none)"),)

    @classmethod
    def from_ports(cls, name, values, children):
        return cls(name, children[0], tags=[values["label"]] if values["label"] else [])

    def __init__(self, name: str, child: py_trees.behaviour.Behaviour, tags: list[str]) -> None:
        super().__init__(name=name, child=child)
        self.tags = tags

    def port_values(self) -> dict:
        return {"label": self.tags[0] if self.tags else None}

    def update(self) -> py_trees.common.Status:
        return self.decorated.status


@pytest.fixture
def user_nodes():
    register_node(Wave)
    register_node(Twice, "RunTwice")
    yield
    for tag in ("Wave", "RunTwice"):
        REGISTRY.pop(tag, None)


def test_a_new_behaviour_is_its_class_plus_one_registration(user_nodes):
    root = py_trees.composites.Sequence(
        "s", True, children=[Wave("hello", "Alice", times=3), Twice("again", Wave("bye", "Bob", pause_s=0.5), ["x"])]
    )
    text = xmltree.to_xml(root)
    assert '<Wave name="hello" who="Alice" times="3"/>' in text
    assert '<RunTwice name="again" label="x">' in text and 'pause_s="0.5"' in text
    assert '<Action ID="Wave">' in text and '<Decorator ID="RunTwice">' in text
    assert '<input_port name="times" type="int" default="1"/>' in text  # the ports the file writes
    assert '<input_port name="times" type="int" default="1">how often</input_port>' in xmltree.to_xml(
        root, model="full"
    )
    reloaded = xmltree.from_xml(text)
    assert list(xmltree.iter_structure(reloaded)) == list(xmltree.iter_structure(root))
    wave, twice = reloaded.children
    assert (type(wave), wave.who, wave.times, wave.pause_s) == (Wave, "Alice", 3, None)
    assert (type(twice), twice.tags, twice.decorated.pause_s) == (Twice, ["x"], 0.5)
    assert xmltree.to_xml(reloaded) == text


def test_a_new_behaviour_gets_the_readers_checks(user_nodes):
    with pytest.raises(XmlTreeError, match=r"line 1: <Wave> needs port 'who' \(std::string\)"):
        xmltree.from_xml(document('<Wave name="w"/>'))
    with pytest.raises(XmlTreeError, match=r"<Wave name='w'> times='often' is not a int"):
        xmltree.from_xml(document('<Wave name="w" who="A" times="often"/>'))


def test_registering_a_class_without_ports_or_with_ports_its_constructor_lacks_is_refused():
    class Silent(py_trees.behaviours.Success):
        pass

    class Odd(py_trees.behaviours.Success):
        @classmethod
        def provided_ports(cls):
            return (Port("colour", STRING, ""),)

    class Named(Odd):
        @classmethod
        def provided_ports(cls):
            return (Port("name", STRING, ""),)

    with pytest.raises(XmlTreeError, match="declares no provided_ports"):
        register_node(Silent)
    with pytest.raises(XmlTreeError, match=r"Odd\(\) takes no colour"):
        register_node(Odd)
    with pytest.raises(XmlTreeError, match="port 'name' is reserved"):
        register_node(Named, "Named")
    assert not {"Silent", "Odd", "Named"} & set(REGISTRY)


def test_a_class_decorator_registers_a_node_with_its_ports_in_the_registration():
    @register_node(ports=(Port("height_m", DOUBLE, 0.05, "how high"),), description="lift the part")
    class Lift(py_trees.behaviours.Success):
        def __init__(self, name: str, height_m: float = 0.05) -> None:
            super().__init__(name)
            self.height_m = height_m

    @register_node
    class Rest(py_trees.behaviours.Success):
        @classmethod
        def provided_ports(cls) -> tuple[Port, ...]:
            return ()

    @register_node("TakeABreak")
    class Pause(Rest):
        pass

    try:
        assert (REGISTRY["Lift"].cls, REGISTRY["Rest"].cls, REGISTRY["TakeABreak"].cls) == (Lift, Rest, Pause)
        assert Lift.provided_ports() == REGISTRY["Lift"].ports and Lift.node_description == "lift the part"
        root = py_trees.composites.Sequence("s", True, children=[Lift("up", 0.1), Rest("r"), Pause("p")])
        text = xmltree.to_xml(root)
        assert '<Lift name="up" height_m="0.1"/>' in text and '<TakeABreak name="p"/>' in text
        palette = xmltree.to_xml(root, model="full")  # an editor's palette: every port, described
        assert '<input_port name="height_m" type="double" default="0.05">how high</input_port>' in palette
        assert '<Metadata description="lift the part"/>' in palette
        reloaded = xmltree.from_xml(text)
        assert [type(node) for node in reloaded.children] == [Lift, Rest, Pause]
        assert reloaded.children[0].height_m == 0.1

        from bt_arrange.display.rendering import text_tree

        assert "<TakeABreak (Pause)> p" in text_tree(root) and "<Lift> up" in text_tree(root)
    finally:
        for tag in ("Lift", "Rest", "TakeABreak"):
            REGISTRY.pop(tag, None)


def test_a_users_node_never_takes_the_tag_of_one_of_ours():
    ours = REGISTRY["Push"]

    class Push(py_trees.behaviours.Success):
        pass

    with pytest.raises(XmlTreeError, match=r"node Push: the tag is bt_arrange\.behaviours\.push\.Push's"):
        register_node(ports=())(Push)
    with pytest.raises(XmlTreeError, match=r"the tag is py_trees\..*register yours under another"):
        register_node(Push, "Sequence", ports=())
    assert REGISTRY["Push"] is ours
    with pytest.raises(XmlTreeError, match=r"declares no provided_ports\(\) \(or give register_node ports=\)"):
        register_node(Push, "MyPush")


# ----------------------------------------------------------------------------------------------
# The codecs' errors belong to the project's error family
# ----------------------------------------------------------------------------------------------


def test_a_codec_error_of_any_kind_is_a_port_value_error():
    def key_error(text):
        return {"a": 1}[text]

    def bt_error(text):
        raise BtArrangeError("no such thing")

    for parse in (key_error, bt_error, int, lambda text: text.split(",")[3]):
        with pytest.raises(PortValueError) as caught:
            PortType("Thing", parse, str).parse("b")
        assert isinstance(caught.value, BtArrangeError) and isinstance(caught.value, ValueError)
        assert str(caught.value).startswith("'b' is not a Thing: ") and caught.value.value == "b"


@pytest.mark.parametrize(
    ("port_type", "text"),
    [
        (DOUBLE, "inf"),
        (INT, "1.5"),
        (OBJECT_TYPE, "bar=0.1*0.1"),
        (RELEASE, "z;0.06"),
        (COLOURS, "teal:rgb:0.1,0.2"),
        (COLOURS, "teal:rgb:2,3,4"),  # PerceptionError inside the colour table
        (COLOURS, "teal:hsv:400-500,0-1,0-1"),
        (xmltree.TARGETS, "red,0.5"),
    ],
)
def test_the_project_codecs_raise_port_value_errors(port_type, text):
    with pytest.raises(PortValueError, match=f"is not a {port_type.name}: "):
        port_type.parse(text)


@pytest.mark.parametrize(
    ("node", "port", "text"),
    [
        ('<Detect name="look" obj="red" object_type="{}"/>', "object_type", "bar=a*b*c"),
        ('<Detect name="look" obj="red" kind_targets="{}"/>', "kind_targets", "0.5,0.1"),
        ('<Inspect name="look" obj="red" after_placing="{}"/>', "after_placing", "maybe"),
        ('<Push name="look" obj="red" yaw_threshold_deg="{}"/>', "yaw_threshold_deg", "nan"),
        (
            '<Arrangement name="look" targets="red,0.5,0.0,0.0" threshold_mm="1" colours="{}"><MoveHome/>'
            "</Arrangement>",
            "colours",
            "teal:rgb:2,3,4",
        ),
        ('<Arrangement name="look" targets="{}" threshold_mm="1"><MoveHome/></Arrangement>', "targets", "red;0.5"),
    ],
)
def test_a_bad_port_text_is_a_one_line_xml_error_naming_node_port_and_value(node, port, text):
    xml = textwrap.dedent(
        f"""\
        <root BTCPP_format="4">
          <BehaviorTree ID="t">
            {node.format(text)}
          </BehaviorTree>
        </root>
        """
    )
    with pytest.raises(XmlTreeError) as caught:
        xmltree.from_xml(xml, source="bad.xml")
    message = str(caught.value)
    tag = node[1 : node.index(" ")]
    assert message.startswith(f"bad.xml line 3: <{tag} name='look'> {port}={text!r} is not a "), message
    assert "\n" not in message and isinstance(caught.value.__cause__, PortValueError)


def test_a_value_its_port_type_cannot_write_names_the_node_and_the_port():
    from bt_arrange.behaviours import Pick

    pick = Pick("pick red", "red")
    pick.grasp = "y;0.06"  # a text, not a Release
    with pytest.raises(XmlTreeError, match=r"cannot write 'pick red' as XML: <Pick> grasp='y;0.06' is not a Release"):
        xmltree.to_xml(pick)
