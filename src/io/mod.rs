//! Image output.
