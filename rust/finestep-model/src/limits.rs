//! The rated rate (docs/spec/rated_rate.md): the increments within which `rate_error`
//! never sets and the output position stays within one step of the ideal one.
//!
//! It is the interface's statement of the specification, [`finestep_interface::rate`],
//! re-exported here: the model never computes with it, its tests check the model's
//! pulse trains against it.

pub use finestep_interface::rate::*;
