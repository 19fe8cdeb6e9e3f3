//! Deforming entities (the deformable paper, Sec. 4 and App. A–B).
