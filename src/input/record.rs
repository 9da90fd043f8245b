//! STUB until the record module lands.
