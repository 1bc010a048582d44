//! Refusals of a value a scene gave: the key, the value and why. Shared by the force terms' and
//! the integrators' specs; the scene layer shows each as `key = value: reason` (exit 2).

/// A key's value that cannot be used: the key, the value and why.
#[derive(Debug, Clone, thiserror::Error)]
#[error("{key} = {value}: {reason}")]
pub struct Invalid {
    pub key: String,
    pub value: String,
    pub reason: String,
}

/// An [`Invalid`] value.
pub fn invalid(key: impl Into<String>, value: impl std::fmt::Display, reason: impl Into<String>) -> Invalid {
    Invalid { key: key.into(), value: value.to_string(), reason: reason.into() }
}

/// Refuses `v` unless it is positive and finite.
pub fn positive(key: &str, v: f64) -> Result<(), Invalid> {
    if v > 0.0 && v.is_finite() {
        Ok(())
    } else {
        Err(invalid(key, v, "must be a positive finite number"))
    }
}

/// Refuses `v` unless it is zero or positive and finite.
pub fn non_negative(key: &str, v: f64) -> Result<(), Invalid> {
    if v >= 0.0 && v.is_finite() {
        Ok(())
    } else {
        Err(invalid(key, v, "must be zero or positive"))
    }
}
