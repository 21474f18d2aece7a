//! Shared helpers for the integration tests (independent reference computations).
#![deny(missing_docs)]
