//! Triangulated irregular network (placeholder, filled in below).
