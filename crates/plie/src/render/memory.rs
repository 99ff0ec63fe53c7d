//! Memory for an image (SPEC §6): a render asks for its largest buffers up front, so that an image
//! too large for the machine is a one-line error instead of the abort a failed allocation is.

use crate::error::{Error, Result};

/// Fails if `bytes` for a `width` x `height` image with `k` x `k` eye rays per pixel cannot be
/// allocated now (asked for and given back at once; the buffers themselves come later).
pub fn check(bytes: u128, (width, height, k): (u32, u32, u32)) -> Result<()> {
    let fits = usize::try_from(bytes).is_ok_and(|b| Vec::<u8>::new().try_reserve_exact(b).is_ok());
    if fits {
        return Ok(());
    }
    Err(Error::InvalidParameter(format!(
        "a {width}x{height} image with {k}x{k} eye rays per pixel needs about {bytes} bytes, more than this \
         machine can allocate; render it smaller"
    )))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn what_cannot_be_allocated_is_an_error() {
        assert!(check(1 << 20, (16, 16, 1)).is_ok());
        let e = check(1 << 62, (32768, 32768, 8)).unwrap_err().to_string();
        assert!(e.contains("32768x32768") && e.contains("more than this machine can allocate"), "{e}");
        assert!(check(u128::MAX, (1, 1, 1)).is_err());
    }
}
