"""``bladecam verify``: an independent re-check of a written plan folder, by meaning: what it reads
(read), what it reports (report), the two cutters together (cutters), each cutter's coverage of its
paths (coverage) and its axis table (axes); ``core.verify.check.verify`` runs them all."""
