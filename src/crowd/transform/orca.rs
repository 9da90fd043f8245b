//! The ORCA baseline of formation-transform section 5.4. CONTRACT ONLY.
