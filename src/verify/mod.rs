//! Cross-verification studies that run the same scenes in magdem and the reference codes.

pub mod contact_cases;
pub mod contacts;
pub mod contacts_report;
pub mod magnetic;
