"""How the robot moves: its inverse kinematics (`ik`), joint-space control (`control`), the base's navigation
over the floor plan (`navigation`), clearance checks against the apartment (`clearance`) and the arm's movement
primitives that the skills are built from (`arm`)."""
