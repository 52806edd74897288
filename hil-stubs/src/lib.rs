//! Firmware board glue (placeholder until the firmware issue).
#![no_std]
