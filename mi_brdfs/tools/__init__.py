"""The ``mi-brdfs`` command (:mod:`.cli`) and what it runs: :mod:`.compare`,
:mod:`.validate`, :mod:`.bench`, :mod:`.fit`, :mod:`.explore`, and the tools
they share (:mod:`.analysis`, :mod:`.chi2`, :mod:`.groundtruth`, :mod:`.tables`)."""
