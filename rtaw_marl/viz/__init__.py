"""Pictures: episode GIFs (:mod:`.gif`) and training plots (:mod:`.plots`)."""
