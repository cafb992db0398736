//! Bot protocol v1.
