"""Scenario tests (SPEC §8): the file format (:mod:`.spec`), the runner
(:mod:`.runner`), JUnit XML (:mod:`.junit`) and line coverage (:mod:`.coverage`)."""
