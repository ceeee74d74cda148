//! The closed-loop guidance benchmark (`foxhunt bench --scenario guidance`): the terrains, the
//! driving policies compared, and the runs.

pub mod bench;
pub mod networks;
pub mod policy;
