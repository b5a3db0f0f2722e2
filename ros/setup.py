"""ament_python package of the softtip ROS 2 node (built by colcon in a ROS 2 workspace)."""

from glob import glob

from setuptools import setup

PACKAGE = "softtip_ros"

setup(
    name=PACKAGE,
    version="0.2.0",
    packages=[PACKAGE],
    data_files=[
        ("share/ament_index/resource_index/packages", [f"resource/{PACKAGE}"]),
        (f"share/{PACKAGE}", ["package.xml"]),
        (f"share/{PACKAGE}/launch", glob("launch/*.launch.py")),
        (f"share/{PACKAGE}/config", glob("config/*.yaml")),
    ],
    # softtip itself is installed with pip beside ROS's Python (see the docs): colcon does not
    # resolve PyPI requirements, so it is not listed in install_requires
    install_requires=["setuptools"],
    zip_safe=True,
    maintainer="softtip developers",
    maintainer_email="maintainers@softtip.invalid",
    description="The softtip ROS 2 node: contact point, state and edge direction from a wrench topic.",
    license="BSD-3-Clause",
    entry_points={"console_scripts": [f"softtip_node = {PACKAGE}.node:main"]},
)
