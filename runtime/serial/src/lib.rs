//! The Khepera serial protocol, both ways (`../shared/reference/khepera.md`): this crate owns
//! the protocol's text ([`protocol`]), the links it travels over ([`link`]), a real-robot
//! backend of the Khepera API ([`client`]) and a simulated robot that answers like a real one
//! ([`server`]). A controller written against `regatta_runtime::khepera` runs unchanged on
//! either side, and a program in any language that drives a real Khepera drives a served one.

pub mod client;
pub mod link;
pub mod protocol;
pub mod server;

pub use client::{ClientOptions, RemoteKhepera};
pub use link::Link;
pub use server::{Ended, Pacing, ServeStats, Server};
