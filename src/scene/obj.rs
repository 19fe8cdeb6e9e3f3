//! OWNED BY THE SCENE WORK ITEM — OBJ/MTL loading with tobj (placeholder).
