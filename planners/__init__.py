"""The robot: grasp candidates (`grasps`), how it moves (`motion`), its skills (`skills`, with `Robot`), the
regression suites of those skills (`suites`) and the names of its MJCF (`robot`). Its numbers are one
`homer_sim.robot_spec.RobotSpec`."""
