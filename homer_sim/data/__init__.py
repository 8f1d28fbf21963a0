"""The data: day files and their format, dataset generation (the person's days simulated and observed), and
dataset statistics."""
