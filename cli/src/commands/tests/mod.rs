//! The command line's machinery: the exit code each kind of error gets, and every parser of
//! what a user hands the command line replayed on the fuzzers' corpus.

mod corpus;

use vklens::Error;

/// The exit code follows the error's kind: 2 for what the user can fix (bad input, a path
/// that cannot be used, work the device cannot do), 1 for the rest. `cli/tests/it/cli.rs` checks that
/// every command exits with it.
#[test]
fn exit_codes_follow_the_error_kind() {
    use super::exit_code;
    let missing = std::io::Error::from(std::io::ErrorKind::NotFound);
    let full = std::io::Error::from(std::io::ErrorKind::StorageFull);
    let p = std::path::Path::new("x.png");
    assert_eq!(exit_code(&Error::input("bad")), 2);
    assert_eq!(exit_code(&Error::unsupported("too big")), 2);
    assert_eq!(exit_code(&Error::io(p, "cannot read", &missing)), 2);
    assert_eq!(exit_code(&Error::io(p, "cannot write", &full)), 1);
    assert_eq!(exit_code(&Error::internal("bug")), 1);
    assert_eq!(
        exit_code(&Error::Vulkan {
            call: "vkQueueSubmit",
            result: ash::vk::Result::ERROR_DEVICE_LOST,
        }),
        1
    );
}
