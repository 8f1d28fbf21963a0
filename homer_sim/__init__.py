"""homer-sim: proactive robot assistance in physics (a MuJoCo apartment, a scripted person, scene graphs)."""

__version__ = "0.2.0"
