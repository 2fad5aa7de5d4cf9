//! BVH (placeholder, being written).
