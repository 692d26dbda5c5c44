//! anisospec: design Monte Carlo sample patterns with anisotropic spectra, and measure what they buy.
//!
//! The modules follow the pipeline of DESIGN §1: [`samplers`] make [`points`], whose [`spectrum`] is
//! computed exactly or by NUFFT and viewed as radial, anisotropy and cone profiles; [`output`] writes
//! npy, EXR, PNG and CSV.
//!
#![doc = include_str!("design.md")]

pub mod cli;
pub mod compare;
pub mod converge;
pub mod error;
pub mod exact_array;
pub mod input;
pub mod integrands;
pub mod optimize;
pub mod output;
pub mod points;
pub mod progress;
pub mod quad;
pub mod render;
pub mod rng;
pub mod samplers;
pub mod spectrum;
pub mod stats;
pub mod targets;
pub mod variance;

pub use error::{Error, Result};
