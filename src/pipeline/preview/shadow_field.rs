//! `gradtrace preview shadow-field`: precompute (cached) → shade → reference → preview.json.
