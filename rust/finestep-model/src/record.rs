//! The period record: every axis's increment for one period, and the flags. The type
//! and the layout are the interface's ([`finestep_interface::PeriodRecord`],
//! docs/interface.md), re-exported here.

pub(crate) use finestep_interface::raw_acceptable;
pub use finestep_interface::{flags, PeriodRecord};
