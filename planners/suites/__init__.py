"""Regression suites of the robot's skills in physics: the grasp suite (`grasp_suite`); its command is in
`scenarios.cli.robot`."""
