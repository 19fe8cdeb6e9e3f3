//! Glossy transfer: adaptive precomputed radiance transfer with von Mises–Fisher lobes, rendered from vMF-prefiltered environment levels.
