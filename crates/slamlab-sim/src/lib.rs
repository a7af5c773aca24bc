//! SLAM Lab simulation (in progress).
