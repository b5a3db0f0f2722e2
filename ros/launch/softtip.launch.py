"""Launch the softtip node with its parameters file.

    ros2 launch softtip_ros softtip.launch.py
    ros2 launch softtip_ros softtip.launch.py params_file:=/path/to/my_params.yaml

The parameters are documented in ``config/params.yaml`` (the defaults of
``softtip.ros.node.PARAMETERS``).
"""

from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument
from launch.substitutions import LaunchConfiguration, PathJoinSubstitution
from launch_ros.actions import Node
from launch_ros.substitutions import FindPackageShare


def generate_launch_description() -> LaunchDescription:
    params_file = LaunchConfiguration("params_file")
    return LaunchDescription(
        [
            DeclareLaunchArgument(
                "params_file",
                default_value=PathJoinSubstitution([FindPackageShare("softtip_ros"), "config", "params.yaml"]),
                description="YAML file of the softtip node's parameters",
            ),
            Node(
                package="softtip_ros",
                executable="softtip_node",
                name="softtip",
                parameters=[params_file],
                output="screen",
            ),
        ]
    )
