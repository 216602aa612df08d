"""The ``mi-brdfs`` command (:mod:`.cli`) and what it runs: :mod:`.render`,
:mod:`.compare`, :mod:`.validate`, :mod:`.bench`, :mod:`.fit`, :mod:`.explore`,
and the tools they share (:mod:`.analysis`, :mod:`.chi2`, :mod:`.groundtruth`, :mod:`.tables`;
below them all :mod:`.errors`, :mod:`.arguments`, :mod:`.settings`,
:mod:`.measures`, :mod:`.pages`, :mod:`.destinations` and :mod:`.progress`).
Where each belongs: the site's "Code layout" page."""
