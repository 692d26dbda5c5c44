//! The depth-of-field renderer integrand (DESIGN §5, issue 4): a small analytic Cornell-box scene seen
//! through a thin lens with a square aperture, each pixel a 4D integrand `f_p(x, y, u, v)`, the depth
//! oracle that turns depth into shear, whole-image rendering with any 4D sampler (sheared or not), and
//! a pixel's slice spectra.

pub mod camera;
pub mod image;
pub mod oracle;
pub mod pixel;
pub mod scene;
pub mod spectrum;

pub use pixel::{parse_pixel_spec, PixelIntegrand};
pub use scene::{Scene, SceneConfig};
