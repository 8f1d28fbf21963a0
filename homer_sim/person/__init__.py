"""The person: the capsule avatar, the executor that carries out script actions in physics, the script
language and activities, households' habits and the routine sampler, and the names of HOMER's vocabulary."""
