//! Image error against a reference (docs/design.md §9), for tests, benchmarks and quality
//! tools; not used to draw. [`metrics`]: PSNR, holes and spill; [`perceptual`]: FLIP
//! and SSIM against a supersampled reference. Built with the `eval` feature.

pub mod metrics;
pub mod perceptual;
