//! Browser entry point (written by the web build work).
