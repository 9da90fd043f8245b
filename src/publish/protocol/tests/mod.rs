//! Unit and property tests of the wire protocol, one file per operation (encoders,
//! decoder, parser), with the snapshots they share in `fixtures`.

mod binary;
mod edit_commands;
mod fixtures;
mod gesture;
mod json;
mod messages;
mod numbers;
mod parse;
