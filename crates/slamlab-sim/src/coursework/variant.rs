//! A student's variant: the seed of their own run, derived from any text that
//! names them (an e-mail address, a matriculation number), the same in the
//! browser and on the command line.
//!
//! `seed = the first 8 bytes, little-endian, of SHA-256("slamlab-variant/1\n" +
//! assignment id + "\n" + student)`, the student's text trimmed and in ASCII lower
//! case (so `Ada@Uni.edu ` and `ada@uni.edu` are one student). The assignment's id
//! is part of it, so one student's two assignments have unrelated noise.

use serde::Serialize;
use sha2::{Digest, Sha256};

/// One student's variant of one assignment.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Variant {
    /// The assignment's id.
    pub assignment: String,
    /// The student's text, as given (trimmed).
    pub student: String,
    /// The seed of every random stream of the run.
    pub seed: u64,
    /// A short name of the variant for screens and reports: the seed's first
    /// 8 hexadecimal digits.
    pub code: String,
}

impl Variant {
    /// The variant of `assignment` for `student`.
    pub fn new(assignment: &str, student: &str) -> Variant {
        let student = student.trim();
        let mut hash = Sha256::new();
        hash.update(b"slamlab-variant/1\n");
        hash.update(assignment.as_bytes());
        hash.update(b"\n");
        hash.update(student.to_ascii_lowercase().as_bytes());
        let digest = hash.finalize();
        let mut first = [0u8; 8];
        first.copy_from_slice(&digest[..8]);
        let seed = u64::from_le_bytes(first);
        Variant {
            assignment: assignment.to_owned(),
            student: student.to_owned(),
            seed,
            code: hex(&digest[..4]),
        }
    }
}

/// The SHA-256 of `bytes`, in lower-case hexadecimal (what `sha256sum` prints).
pub fn sha256_hex(bytes: &[u8]) -> String {
    hex(&Sha256::digest(bytes))
}

fn hex(bytes: &[u8]) -> String {
    use std::fmt::Write as _;
    let mut out = String::with_capacity(2 * bytes.len());
    for b in bytes {
        let _ = write!(out, "{b:02x}");
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The seed of `ada@uni.edu`'s `ekf-slam` variant.
    const PINNED_SEED: u64 = 17_806_707_086_622_733_865;

    #[test]
    fn a_student_has_one_seed_and_two_students_two() {
        let a = Variant::new("ekf-slam", "ada@uni.edu");
        let same = Variant::new("ekf-slam", "  Ada@Uni.EDU ");
        assert_eq!((a.seed, &a.code), (same.seed, &same.code));
        assert_eq!(same.student, "Ada@Uni.EDU");
        assert_ne!(a.seed, Variant::new("ekf-slam", "alan@uni.edu").seed);
        assert_ne!(a.seed, Variant::new("mcl", "ada@uni.edu").seed);
        // Pinned: the browser and the command line derive the same seed, and
        // a change of the derivation would hand every student new inputs.
        assert_eq!(a.seed, PINNED_SEED);
        assert_eq!(a.code, format!("{:08x}", (a.seed as u32).swap_bytes()));
    }

    #[test]
    fn sha256_is_the_standard_one() {
        assert_eq!(
            sha256_hex(b"abc"),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
        );
        assert_eq!(
            sha256_hex(b""),
            "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855"
        );
    }
}
