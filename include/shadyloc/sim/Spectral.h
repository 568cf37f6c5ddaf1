/* ShadyLoc simulator — spectra: illuminants, reflectances, camera sensitivities.
 *
 * Everything is sampled on one wavelength grid (default 400-700 nm, 10 nm).
 * The rendering integral of a Lambertian surface under an illuminant,
 *
 *     R_k = integral S_k(l) * E(l) * rho(l) / pi  dl      (k = blue, green, red)
 *
 * is linear in the illuminant E and in the reflectance rho, so the renderer
 * precomputes R_k once per (material basis spectrum, illuminant) pair per
 * traversal and mixes those 3-vectors per pixel: exact spectral rendering of
 * the model at the cost of an RGB renderer.
 */
#pragma once

#include <array>
#include <string>
#include <vector>

namespace shadyloc::sim
{
/** Samples of a spectral quantity on a WavelengthGrid. */
using Spectrum = std::vector<double>;

/** Channel responses, index 0 = blue (shortest peak), 1 = green, 2 = red:
 * the same order as the BGR bytes MRPT and OpenCV store. */
using Rgb = std::array<double, 3>;

/** Uniform wavelength sampling of the visible band. */
struct WavelengthGrid
{
	double min_nm = 400.0;	//!< first sample (nm)
	double max_nm = 700.0;	//!< last sample (nm), included
	double step_nm = 10.0;	//!< spacing (nm)

	size_t size() const;
	double at(size_t i) const { return min_nm + step_nm * static_cast<double>(i); }
	/** Throws std::invalid_argument if the grid is empty or degenerate. */
	void validate() const;
};

/** Planck's law for a black body at temperature T (K), relative spectral
 * radiance normalised to 1 at 560 nm (the absolute level is set apart). */
Spectrum planckian(const WavelengthGrid& g, double temperature_K);
/** Planck's law at one wavelength (nm), unnormalised (W sr^-1 m^-3 scale). */
double planck(double lambda_nm, double temperature_K);

/** Gaussian sensitivity exp(-(l-peak)^2 / (2 sigma^2)), peak value 1. */
Spectrum gaussian(const WavelengthGrid& g, double peak_nm, double sigma_nm);

/** A smooth reflectance curve: base + sum of Gaussian lobes + sum of
 * logistic steps, clamped to [0.005, 0.98]. */
struct ReflectanceModel
{
	struct Lobe
	{
		double centre_nm, width_nm, amplitude;
	};
	double base = 0.1;			//!< flat part (fraction)
	std::vector<Lobe> lobes;	//!< Gaussian bumps, width = sigma (nm)
	std::vector<Lobe> steps;	//!< logistic rises at centre, width = scale (nm)
	Spectrum sample(const WavelengthGrid& g) const;
};

/** sum_l a(l) b(l) c(l) step / pi: the camera response of a Lambertian
 * reflectance b under irradiance c for sensitivity a. */
double integrate3(const Spectrum& a, const Spectrum& b, const Spectrum& c, double step_nm);

/** The three channel sensitivities of a camera, with a fixed white balance. */
struct CameraSpectralModel
{
	std::array<double, 3> peak_nm{{470.0, 540.0, 620.0}};  //!< blue, green, red peaks (nm)
	double sigma_nm = 30.0;	 //!< Gaussian width (standard deviation, nm) of every channel
	/** Fixed white balance: per-channel gains making a white surface under a
	 * black body at this temperature (K) give equal responses; 0 = unit gains.
	 * Fixed, not automatic, so that every traversal shares one camera. */
	double white_balance_K = 6500.0;

	/** Sensitivities times white-balance gains, on grid g. */
	std::array<Spectrum, 3> sensitivities(const WavelengthGrid& g) const;
	void validate() const;
};

/** Camera response to a reflectance under an illuminant (both on grid g). */
Rgb response(
	const std::array<Spectrum, 3>& sens, const Spectrum& illuminant, const Spectrum& reflectance,
	double step_nm);

/** Reference alpha of a camera for the invariant I = log R2 - alpha log R1 -
 * (1 - alpha) log R3 (beta = 1 - alpha): the alpha minimising the variance of
 * I over black-body illuminants from T_min to T_max (Planck's law, n
 * temperatures uniform in reciprocal temperature, the scale on which the
 * Wien term moves log responses), pooled over the given reflectances (their
 * within-reflectance variances summed; a flat reflectance if none). Closed
 * form: with x = log(R1/R3), y = log(R2/R3), I = y - alpha x, so
 * alpha = sum cov(x, y) / sum var(x). Unlike the peak-wavelength formula it
 * accounts for the sensors' bandwidth. */
double blackBodyReferenceAlpha(
	const std::array<Spectrum, 3>& sens, const WavelengthGrid& g, const std::vector<Spectrum>& reflectances = {},
	double T_min_K = 2500.0, double T_max_K = 20000.0, int n = 64);

}  // namespace shadyloc::sim
