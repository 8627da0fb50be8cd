"""The spec's generated controller as a ROS 2 node (``fuzzkit ros2``): rclpy, an optional extra.

The node's logic is plain Python that knows no ROS (:mod:`~fuzzkit.ros2.sample_clock`: which
period a stamped sample fills; :mod:`~fuzzkit.ros2.controller`: the generated controller opened
with its run-time parameters, tare and reset; :mod:`~fuzzkit.ros2.parameters`: what a ROS
parameter may be set to; :mod:`~fuzzkit.ros2.watchdog`; :mod:`~fuzzkit.ros2.stepper`: one wrench
sample in, the corrections of the periods it closes out; :mod:`~fuzzkit.ros2.pose_pairing`).
Only :mod:`~fuzzkit.ros2.runtime` (importing rclpy, or saying how to install it),
:mod:`~fuzzkit.ros2.messages` and :mod:`~fuzzkit.ros2.diagnostics` (which import the message
packages when called), and :mod:`~fuzzkit.ros2.node` and :mod:`~fuzzkit.ros2.plant_node`
(rclpy at module scope: imported only after :func:`~fuzzkit.ros2.runtime.require`) touch ROS,
so that the package imports without the extra.

Imports the loop (the plant node's closed loop is :func:`fuzzkit.loop.run.run_loop`), studies
(the generated controller's opening code, the replay's parameter names and
checks, the bag reader's quaternion), control and the errors; never the CLI, the report or
visualisation.
"""
