"""The apartment: its declarative layout, furniture geometry, object catalogue, MuJoCo build, floor plan,
the robot-envelope validator, free spots for placements, and the standalone MJCF export."""
