"""Named headless runs built on the world, the planners and the model: the breakfast demo and its variants
(`scenarios.registry`), the assisted-day loop (`scenarios.assist`) and their command line (`scenarios.cli`)."""
