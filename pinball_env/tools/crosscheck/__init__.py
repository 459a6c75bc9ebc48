"""Cross-check our swept physics against pymunk: ``python -m pinball_env.tools.crosscheck``
(``--out``, ``--trials``, ``--frames``; the ``crosscheck`` extra).

- :mod:`.scenarios`: the scenarios and their tolerances, the tests' oracle (a package: the
  shots and tolerances, the contacts, the cabinet, the targets, several balls);
- :mod:`.report`: the headline figures, the findings in words, the tables on the terminal;
- :mod:`.plots`: the figure, ``crosscheck.png``;
- :mod:`.cli`: the command line, every scenario run into ``crosscheck.json``.
"""
