"""New plugin and pack projects: installable distributions that depend on infuse, made by one command.

- :mod:`~infuse.scaffold.distribution`: the distribution names (``infuse-anim`` and ``infuse-anim-*``),
  the dependency on the core, and the ``pyproject.toml`` of a new project;
- :mod:`~infuse.scaffold.plugin`: ``infuse plugin new KIND NAME``, one working template per plugin kind.

Pack projects (``infuse pack new``) are made by :mod:`infuse.packs.project`.
"""
