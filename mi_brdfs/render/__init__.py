"""The renderer's parts: the scan-line integrator (:mod:`.integrator`),
rendering in passes (:mod:`.passes`), tone mapping (:mod:`.tonemap`) and image
I/O (:mod:`.exr`)."""
