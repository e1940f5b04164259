//! The exoskeleton models.
