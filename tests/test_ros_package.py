"""The ROS 2 package in ``ros/`` (ament_python), checked without ROS.

No ROS 2 installation is available to the tests, so this is what is checked: ``package.xml``
follows format 3 (REP 149: the rules of its XML schema, written out below, and catkin_pkg's
parser, the one colcon, rosdep and bloom use, when installed); the entry point, the data files
and ``setup.cfg`` of the ament_python layout; the launch file, imported with stub ``launch`` and
``launch_ros`` modules; ``config/params.yaml`` against the node's parameters. What is not
checked: ``colcon build``, ``ros2 launch``, and the node against rclpy (docs: the ROS 2 package).
"""

from __future__ import annotations

import configparser
import importlib.util
import re
import sys
import types
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from softtip.ros.node import PARAMETERS

ROS = Path(__file__).resolve().parents[1] / "ros"
PACKAGE = "softtip_ros"

#: REP 149 (format 3): the elements of <package>, in this order; the dependency elements and
#: the groups in any order between author and export
HEAD = ("name", "version", "description")
PEOPLE = ("maintainer", "license", "url", "author")
DEPENDS = {
    "build_depend", "build_export_depend", "buildtool_depend", "buildtool_export_depend", "exec_depend", "depend",
    "doc_depend", "test_depend", "conflict", "replace", "group_depend", "member_of_group",
}  # fmt: skip


def test_package_xml_follows_format_3() -> None:
    root = ET.parse(ROS / "package.xml").getroot()
    assert root.tag == "package" and root.get("format") == "3"
    tags = [child.tag for child in root if isinstance(child.tag, str)]
    assert tuple(tags[:3]) == HEAD, tags
    rest = tags[3:]
    if "export" in rest:
        assert rest.count("export") == 1 and rest[-1] == "export", "export: at most one, last"
        rest = rest[:-1]
    ranks = [PEOPLE.index(t) if t in PEOPLE else len(PEOPLE) for t in rest]
    assert ranks == sorted(ranks), f"maintainer, license, url, author, then dependencies: {rest}"
    assert set(rest) <= set(PEOPLE) | DEPENDS, set(rest) - set(PEOPLE) - DEPENDS
    assert "maintainer" in rest and "license" in rest
    name = root.findtext("name")
    assert name == PACKAGE and re.fullmatch(r"[a-z](?:[a-z0-9_]*[a-z0-9])?", name) and "__" not in name
    assert re.fullmatch(r"(0|[1-9][0-9]*)\.(0|[1-9][0-9]*)\.(0|[1-9][0-9]*)", root.findtext("version"))
    for m in root.iter("maintainer"):
        assert re.fullmatch(r"[^@\s]+@[^@\s]+\.[^@\s]+", m.get("email", "")), "maintainer needs an email"
    for u in root.iter("url"):
        assert u.get("type", "website") in ("website", "bugtracker", "repository")
    for dep in root:
        if dep.tag in DEPENDS:
            assert dep.text and dep.text.strip() and set(dep.attrib) <= {
                "version_lt", "version_lte", "version_eq", "version_gte", "version_gt", "condition"}  # fmt: skip
    assert root.find("export/build_type").text == "ament_python"
    assert root.find("buildtool_depend").text == "ament_python"
    assert {d.text for d in root.iter("exec_depend")} >= {"rclpy", "geometry_msgs", "std_msgs", "std_srvs",
                                                          "visualization_msgs", "launch", "launch_ros"}  # fmt: skip


def test_package_xml_parses_with_catkin_pkg() -> None:
    package = pytest.importorskip("catkin_pkg.package", reason="catkin_pkg not installed (the test extra has it)")
    pkg = package.parse_package(str(ROS / "package.xml"))
    pkg.validate()  # raises InvalidPackage
    assert pkg.package_format == 3 and pkg.name == PACKAGE
    assert [e.content for e in pkg.exports if e.tagname == "build_type"] == ["ament_python"]


def test_setup_py_installs_the_node_and_the_ament_files() -> None:
    text = (ROS / "setup.py").read_text(encoding="utf-8")
    assert re.search(r'"softtip_node = \{PACKAGE\}\.node:main"', text)
    assert 'PACKAGE = "softtip_ros"' in text
    for needed in ("share/ament_index/resource_index/packages", "resource/{PACKAGE}", "package.xml",
                   "launch/*.launch.py", "config/*.yaml"):  # fmt: skip
        assert needed in text, needed
    assert (ROS / "resource" / PACKAGE).is_file()
    version = ET.parse(ROS / "package.xml").getroot().findtext("version")
    assert f'version="{version}"' in text, "setup.py and package.xml give one version"
    cfg = configparser.ConfigParser()
    cfg.read(ROS / "setup.cfg")
    assert cfg["develop"]["script_dir"] == cfg["install"]["install_scripts"] == f"$base/lib/{PACKAGE}"


def test_the_entry_point_runs_the_node_and_asks_for_ros(monkeypatch) -> None:
    """Without rclpy the node stops with the message to source ROS 2 (the entry point reaches it)."""
    spec = importlib.util.spec_from_file_location("softtip_ros_node", ROS / PACKAGE / "node.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    if importlib.util.find_spec("rclpy") is not None:  # pragma: no cover - a ROS 2 shell
        pytest.skip("rclpy is importable here: the node would start")
    with pytest.raises(SystemExit, match="source your ROS 2 installation"):
        mod.main([])


class _Recorded:
    """A stub launch class: remembers how it was made."""

    def __init__(self, *args, **kwargs):
        self.args, self.kwargs = args, kwargs

    def __eq__(self, other):
        return type(self) is type(other) and (self.args, self.kwargs) == (other.args, other.kwargs)

    def __repr__(self):
        return f"{type(self).__name__}{self.args}{self.kwargs}"


def _stub_launch(monkeypatch) -> dict[str, type]:
    classes = {}
    for module, names in {
        "launch": ["LaunchDescription"],
        "launch.actions": ["DeclareLaunchArgument"],
        "launch.substitutions": ["LaunchConfiguration", "PathJoinSubstitution"],
        "launch_ros": [],
        "launch_ros.actions": ["Node"],
        "launch_ros.substitutions": ["FindPackageShare"],
    }.items():
        mod = types.ModuleType(module)
        for name in names:
            classes[name] = type(name, (_Recorded,), {})
            setattr(mod, name, classes[name])
        monkeypatch.setitem(sys.modules, module, mod)
    return classes


def test_the_launch_file_imports_and_starts_the_node_with_its_parameters(monkeypatch) -> None:
    c = _stub_launch(monkeypatch)
    spec = importlib.util.spec_from_file_location("softtip_launch", ROS / "launch" / "softtip.launch.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    ld = mod.generate_launch_description()
    assert isinstance(ld, c["LaunchDescription"])
    (actions,) = ld.args
    declares = [a for a in actions if isinstance(a, c["DeclareLaunchArgument"])]
    nodes = [a for a in actions if isinstance(a, c["Node"])]
    assert len(declares) == 1 and len(nodes) == 1
    assert declares[0].args == ("params_file",)
    assert declares[0].kwargs["default_value"] == c["PathJoinSubstitution"](
        [c["FindPackageShare"](PACKAGE), "config", "params.yaml"]
    )
    node = nodes[0].kwargs
    assert (node["package"], node["executable"], node["name"]) == (PACKAGE, "softtip_node", "softtip")
    assert node["parameters"] == [c["LaunchConfiguration"]("params_file")]


def test_params_yaml_holds_every_parameter_with_its_default() -> None:
    yaml = pytest.importorskip("yaml", reason="PyYAML not installed (the docs extra brings it)")
    doc = yaml.safe_load((ROS / "config" / "params.yaml").read_text(encoding="utf-8"))
    assert list(doc) == ["softtip"], "the node's name (softtip.ros.node: Node('softtip'))"
    params = doc["softtip"]["ros__parameters"]
    assert params == PARAMETERS
    assert all(type(params[k]) is type(v) for k, v in PARAMETERS.items()), "ROS 2 parameters are typed"


def test_params_yaml_is_generated_from_the_settings() -> None:
    """The file is :func:`params_yaml` (the node's and the estimator settings' metadata) to the byte; the
    parameters without a default stand in it as comments."""
    from softtip.ros.node import UNSET_PARAMETERS, params_yaml

    text = (ROS / "config" / "params.yaml").read_text(encoding="utf-8")
    assert text == params_yaml(), (
        "regenerate: python -c 'from softtip.ros.node import params_yaml; print(params_yaml(), end=\"\")' "
        "> ros/config/params.yaml"
    )
    for name in UNSET_PARAMETERS:
        assert re.search(rf"^    # {name}: \[\]  # ", text, re.M), name


#: The node's parameters that no ``softtip estimate`` option has, and why
ROS_ONLY = {
    "wrench_topic": "the topic the node subscribes to",
    "publish_markers": "RViz markers",
    "orientation_topic": "the payload's orientation from a topic (the CLI reads it from the log)",
    "sample_rate": "the commands take it from the data",
}


def test_params_yaml_names_are_the_cli_options() -> None:
    """Every parameter of config/params.yaml is the ``softtip estimate`` option of its name
    (``line_fit_window`` is ``--line-fit-window``), but the node's own few (ROS_ONLY)."""
    import click

    from softtip.cli import main
    from softtip.ros.node import UNSET_PARAMETERS

    cmd = main.commands["estimate"]
    opts = {o for p in cmd.params if isinstance(p, click.Option) for o in p.opts + p.secondary_opts}
    names = [*PARAMETERS, *UNSET_PARAMETERS]
    assert {n for n in names if "--" + n.replace("_", "-") not in opts} == set(ROS_ONLY)
