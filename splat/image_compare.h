/// @file image_compare.h
/// @brief Image error metrics: PSNR, SSIM, FLIP, mean and max absolute error.
///
/// All metrics see the images as a display shows them: linear RGB is clamped to [0,1] and
/// sRGB-encoded first (PNGs already are). PSNR is over the three channels with peak 1. SSIM
/// (Wang et al. 2004) is on luma Y' = 0.2126 R' + 0.7152 G' + 0.0722 B' with an 11x11 Gaussian
/// window of sigma 1.5, K1 = 0.01, K2 = 0.03, edges mirrored. FLIP is the LDR pipeline of
/// Andersson et al. 2020 ("FLIP: A Difference Evaluator for Alternating Images") at 67 pixels
/// per degree by default, written here; its mean over the image is reported.
#pragma once

#include <vector>

#include "noise/image.h"

namespace spot::splat {

struct ImageMetrics {
    double psnr = 0.0;    ///< dB; +inf for identical images
    double ssim = 0.0;    ///< mean SSIM, 1 for identical images
    double flip = 0.0;    ///< mean FLIP in [0,1], 0 for identical images
    double meanAbs = 0.0; ///< mean |a - b| over pixels and channels (display values)
    double maxAbs = 0.0;
    /// Signed mean of b - a over pixels and channels, in linear values and in display values:
    /// positive where the test image is brighter than the reference.
    double meanDiffLinear = 0.0;
    double meanDiffDisplay = 0.0;
    /// Relative bias of the test image's mean brightness, mean(b) / mean(a) - 1 over pixels and
    /// channels in linear values (0 where the reference's mean is 0): +0.11 is 11% too bright.
    /// The whole image counts, background included, so it reads as the fur's own bias where the
    /// fur fills the frame or the background is dark.
    double bias = 0.0;
};

/// Default observer: a 0.7 m wide 3840-pixel monitor seen from 0.7 m (FLIP's default).
inline constexpr double kDefaultPixelsPerDegree = 67.02064327658226;

/// Compare two images of the same size (InputError otherwise). `flipMap`, when given, receives
/// the per-pixel FLIP error.
ImageMetrics compareImages(const noise::Image& reference, const noise::Image& test,
                           std::vector<float>* flipMap = nullptr,
                           double pixelsPerDegree = kDefaultPixelsPerDegree);

double psnr(const noise::Image& reference, const noise::Image& test);
double ssim(const noise::Image& reference, const noise::Image& test);
/// Per-pixel LDR FLIP error; returns the mean.
double flip(const noise::Image& reference, const noise::Image& test, std::vector<float>* errorMap,
            double pixelsPerDegree = kDefaultPixelsPerDegree);

/// An error map in [0,1] as a heat map (black - purple - orange - yellow, like FLIP's magma).
noise::Image heatMap(const std::vector<float>& errors, int width, int height);

} // namespace spot::splat
