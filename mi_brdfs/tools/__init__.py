"""The ``mi-brdfs`` command (:mod:`.cli`) and what it runs: :mod:`.compare`,
:mod:`.validate`, :mod:`.bench`, :mod:`.analysis`, and :mod:`.catalog`, the
configurations the reports, the benchmarks and the tests run."""
