"""Grasp candidates of an object in the apartment, as typed data: what a grasp is (`candidate`), the shape
geometry every generator shares (`geometry`), the generators by where the object stands (`above`: an open top;
`shelf`: inside furniture, from its front; `features`: grip features, rims, pot handles), what stands beside it
(`neighbours`) and the order in which candidates are tried (`ranking`). No mujoco import."""
