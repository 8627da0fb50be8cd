"""rclpy and the message packages, imported on demand, or a clear error saying how to get them.

The ROS 2 Kilted wheels (the ``ros2`` extra: ``pip install 'fuzzkit[ros2]'``) run in a plain
virtual environment with no sourced ROS setup; the one setting the kit makes for them is the
middleware, Fast DDS (``RMW_IMPLEMENTATION=rmw_fastrtps_cpp``, unless the environment names
another), since the extra installs that one and no other. The wheels find their shared
libraries by themselves: their ``ros-wheels-bootstrapper`` restarts the interpreter once, at
start-up, with ``LD_LIBRARY_PATH`` pointing into the environment. rclpy writes its log files
under ``$HOME/.ros/log`` and cannot start without a home folder: with neither ``HOME`` nor
``ROS_HOME`` nor ``ROS_LOG_DIR`` set, the kit points ``ROS_LOG_DIR`` at the temporary folder.
"""

from __future__ import annotations

import os
from types import ModuleType

from fuzzkit.errors import FuzzkitError

#: The command that installs what the node needs.
INSTALL = "pip install 'fuzzkit[ros2]'"
#: The middleware the extra installs.
RMW = "rmw_fastrtps_cpp"
#: What the node imports: rclpy and the message and service packages it speaks.
MODULES = (
    "rclpy",
    "geometry_msgs.msg",
    "std_srvs.srv",
    "diagnostic_msgs.msg",
    "rcl_interfaces.msg",
    "rosgraph_msgs.msg",
)


class Ros2Unavailable(FuzzkitError, RuntimeError):
    """The ROS 2 Python packages are not installed (or do not load)."""


def require() -> dict[str, ModuleType]:
    """Every module of :data:`MODULES` by name, imported with the middleware set.

    Raises
    ------
    Ros2Unavailable
        One of them does not import: the message says how to install the extra.
    """
    import importlib
    import tempfile

    os.environ.setdefault("RMW_IMPLEMENTATION", RMW)
    if not any(os.environ.get(k) for k in ("HOME", "ROS_HOME", "ROS_LOG_DIR")):
        os.environ["ROS_LOG_DIR"] = os.path.join(tempfile.gettempdir(), "ros_log")
    modules = {}
    for name in MODULES:
        try:
            modules[name] = importlib.import_module(name)
        except ImportError as exc:
            raise Ros2Unavailable(
                f"fuzzkit ros2 needs the ROS 2 Python packages (rclpy and the geometry_msgs, "
                f"std_srvs, diagnostic_msgs and rosgraph_msgs messages), which are an optional "
                f"extra: install them with {INSTALL} (importing {name} failed: {exc})"
            ) from None
    return modules
