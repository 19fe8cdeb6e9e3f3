//! Shadow fields (Zhou et al. 2005; deformable extension): per-entity occlusion and source radiance fields in order-4 spherical harmonics, combined per receiver point.
