//! Fitting material laws to test data: the shear law to picture-frame or bias-extension
//! force-displacement curves, the knit tension law to uniaxial stress-strain data.
