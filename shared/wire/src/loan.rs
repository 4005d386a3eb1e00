//! Loaning a sample initialised in place.

use iceoryx2::prelude::*;

/// Loan a sample from `publisher` and initialise its payload in place to its default
/// value: a large message (the 400 kB mission) is never built on the stack and copied.
/// The only in-place initialisation of the protocol; every sender loans through it.
pub fn loan_default<T>(
    publisher: &iceoryx2::port::publisher::Publisher<ipc::Service, T, ()>,
) -> Result<iceoryx2::sample_mut::SampleMut<ipc::Service, T, ()>, iceoryx2::port::LoanError>
where
    T: std::fmt::Debug + ZeroCopySend + PlacementDefault,
{
    let mut sample = publisher.loan_uninit()?;
    // SAFETY: the pointer is the sample's own payload slot, valid, aligned and exclusive;
    // `placement_default` writes every field of a `T` there.
    unsafe { T::placement_default(sample.payload_mut().as_mut_ptr()) };
    // SAFETY: the payload was initialised just above.
    Ok(unsafe { sample.assume_init() })
}
