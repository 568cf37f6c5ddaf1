/* ShadyLoc simulator — spectra. */
#include <shadyloc/sim/Spectral.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace shadyloc::sim
{
size_t WavelengthGrid::size() const
{
	return static_cast<size_t>(std::floor((max_nm - min_nm) / step_nm + 1e-9)) + 1;
}

void WavelengthGrid::validate() const
{
	if (!(step_nm > 0) || !(max_nm > min_nm) || min_nm < 100 || max_nm > 2000)
		throw std::invalid_argument(
			"wavelength grid: need 100 <= lambda_min_nm < lambda_max_nm <= 2000 and lambda_step_nm > 0");
}

double planck(double lambda_nm, double T)
{
	// h c / k = 1.4388e-2 m K; 2 h c^2 = 1.191e-16 W m^2 sr^-1
	const double l = lambda_nm * 1e-9;
	return 1.191042e-16 / (l * l * l * l * l) / std::expm1(1.438777e-2 / (l * T));
}

Spectrum planckian(const WavelengthGrid& g, double T)
{
	if (!(T > 500 && T < 1e6))
		throw std::invalid_argument("black-body temperature out of range (500..1e6 K)");
	const double ref = planck(560.0, T);
	Spectrum s(g.size());
	for (size_t i = 0; i < s.size(); i++) s[i] = planck(g.at(i), T) / ref;
	return s;
}

Spectrum gaussian(const WavelengthGrid& g, double peak, double sigma)
{
	Spectrum s(g.size());
	for (size_t i = 0; i < s.size(); i++)
	{
		const double d = (g.at(i) - peak) / sigma;
		s[i] = std::exp(-0.5 * d * d);
	}
	return s;
}

Spectrum ReflectanceModel::sample(const WavelengthGrid& g) const
{
	Spectrum s(g.size());
	for (size_t i = 0; i < s.size(); i++)
	{
		const double l = g.at(i);
		double r = base;
		for (const auto& b : lobes)
		{
			const double d = (l - b.centre_nm) / b.width_nm;
			r += b.amplitude * std::exp(-0.5 * d * d);
		}
		for (const auto& b : steps) r += b.amplitude / (1.0 + std::exp(-(l - b.centre_nm) / b.width_nm));
		s[i] = std::clamp(r, 0.005, 0.98);
	}
	return s;
}

double integrate3(const Spectrum& a, const Spectrum& b, const Spectrum& c, double step)
{
	double sum = 0;
	for (size_t i = 0; i < a.size(); i++) sum += a[i] * b[i] * c[i];
	return sum * step / M_PI;
}

void CameraSpectralModel::validate() const
{
	if (!(peak_nm[0] < peak_nm[1] && peak_nm[1] < peak_nm[2]))
		throw std::invalid_argument("camera: peak wavelengths must satisfy blue < green < red");
	if (!(sigma_nm > 0.5 && sigma_nm < 200))
		throw std::invalid_argument("camera: sensitivity_sigma_nm must be in (0.5, 200) nm");
	if (white_balance_K != 0 && !(white_balance_K > 1000 && white_balance_K < 1e5))
		throw std::invalid_argument("camera: white_balance_K must be 0 (off) or in (1000, 1e5) K");
}

std::array<Spectrum, 3> CameraSpectralModel::sensitivities(const WavelengthGrid& g) const
{
	std::array<Spectrum, 3> s;
	for (int k = 0; k < 3; k++) s[k] = gaussian(g, peak_nm[k], sigma_nm);
	if (white_balance_K > 0)
	{
		const Spectrum white(g.size(), 1.0);
		const Spectrum E = planckian(g, white_balance_K);
		const double green = integrate3(s[1], E, white, g.step_nm);
		for (int k = 0; k < 3; k++)
		{
			const double gain = green / integrate3(s[k], E, white, g.step_nm);
			for (auto& v : s[k]) v *= gain;
		}
	}
	return s;
}

Rgb response(
	const std::array<Spectrum, 3>& sens, const Spectrum& E, const Spectrum& rho, double step)
{
	return {integrate3(sens[0], E, rho, step), integrate3(sens[1], E, rho, step),
			integrate3(sens[2], E, rho, step)};
}

double blackBodyReferenceAlpha(
	const std::array<Spectrum, 3>& sens, const WavelengthGrid& g, const std::vector<Spectrum>& reflectances,
	double T_min, double T_max, int n)
{
	if (!(T_min > 500 && T_min < T_max && n >= 2))
		throw std::invalid_argument("reference alpha: need 500 < T_min < T_max and n >= 2");
	std::vector<Spectrum> refl = reflectances;
	if (refl.empty()) refl.emplace_back(g.size(), 1.0);
	std::vector<Spectrum> E;
	for (int i = 0; i < n; i++)
	{
		const double mired = 1.0 / T_max + (1.0 / T_min - 1.0 / T_max) * i / (n - 1);
		E.push_back(planckian(g, 1.0 / mired));
	}
	double cxy = 0, cxx = 0;
	for (const auto& rho : refl)
	{
		std::vector<double> xs, ys;
		for (const auto& e : E)
		{
			const Rgb r = response(sens, e, rho, g.step_nm);
			xs.push_back(std::log(r[0] / r[2]));
			ys.push_back(std::log(r[1] / r[2]));
		}
		double mx = 0, my = 0;
		for (int i = 0; i < n; i++) mx += xs[i] / n, my += ys[i] / n;
		for (int i = 0; i < n; i++) cxy += (xs[i] - mx) * (ys[i] - my), cxx += (xs[i] - mx) * (xs[i] - mx);
	}
	return cxy / cxx;
}

}  // namespace shadyloc::sim
