"""The renderer's parts: the scan-line integrator (:mod:`.integrator`),
rendering in passes (:mod:`.passes`) through frozen functions (:mod:`.frozen`,
also for gradient descent), tone mapping (:mod:`.tonemap`) and image I/O
(:mod:`.exr`)."""
