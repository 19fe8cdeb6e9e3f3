//! `gradtrace preview glossy`: precompute transfer (cached) → render views → reference → preview.json.
