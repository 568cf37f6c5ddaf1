/* ShadyLoc simulator — small, fast, deterministic procedural noise and
 * random numbers (lattice value noise with a quintic fade, fractal sums;
 * splitmix64). Integer hashing keeps results identical on every platform and
 * thread count: a pixel's value depends on its coordinates and seeds only. */
#pragma once

#include <cmath>
#include <cstdint>

namespace shadyloc::sim
{
inline uint32_t hash32(uint32_t h)
{
	h ^= h >> 16;
	h *= 0x7feb352dU;
	h ^= h >> 15;
	h *= 0x846ca68bU;
	h ^= h >> 16;
	return h;
}

inline uint32_t hashLattice(int x, int y, int z, uint32_t seed)
{
	// One mixing round over a linear combination with large odd constants:
	// enough for value noise, and the hot path of the leaf field.
	return hash32(
		seed + static_cast<uint32_t>(x) * 0x8da6b343U + static_cast<uint32_t>(y) * 0xd8163841U +
		static_cast<uint32_t>(z) * 0xcb1ab31fU);
}

/** Uniform in [-1, 1] from a hash. */
inline float hashToSigned(uint32_t h) { return static_cast<float>(h >> 8) * (2.0f / 16777215.0f) - 1.0f; }

inline float fade(float t) { return t * t * t * (t * (t * 6.0f - 15.0f) + 10.0f); }
inline float lerpf(float a, float b, float t) { return a + (b - a) * t; }

/** 2D value noise in [-1, 1], unit lattice spacing. */
inline float valueNoise2(float x, float y, uint32_t seed)
{
	const float fx = std::floor(x), fy = std::floor(y);
	const int ix = static_cast<int>(fx), iy = static_cast<int>(fy);
	const float tx = fade(x - fx), ty = fade(y - fy);
	const float a = hashToSigned(hashLattice(ix, iy, 0, seed));
	const float b = hashToSigned(hashLattice(ix + 1, iy, 0, seed));
	const float c = hashToSigned(hashLattice(ix, iy + 1, 0, seed));
	const float d = hashToSigned(hashLattice(ix + 1, iy + 1, 0, seed));
	return lerpf(lerpf(a, b, tx), lerpf(c, d, tx), ty);
}

/** 3D value noise in [-1, 1], unit lattice spacing. */
inline float valueNoise3(float x, float y, float z, uint32_t seed)
{
	const float fx = std::floor(x), fy = std::floor(y), fz = std::floor(z);
	const int ix = static_cast<int>(fx), iy = static_cast<int>(fy), iz = static_cast<int>(fz);
	const float tx = fade(x - fx), ty = fade(y - fy), tz = fade(z - fz);
	float v[2];
	for (int k = 0; k < 2; k++)
	{
		const float a = hashToSigned(hashLattice(ix, iy, iz + k, seed));
		const float b = hashToSigned(hashLattice(ix + 1, iy, iz + k, seed));
		const float c = hashToSigned(hashLattice(ix, iy + 1, iz + k, seed));
		const float d = hashToSigned(hashLattice(ix + 1, iy + 1, iz + k, seed));
		v[k] = lerpf(lerpf(a, b, tx), lerpf(c, d, tx), ty);
	}
	return lerpf(v[0], v[1], tz);
}

/** Fractal sum of 2D value noise (gain 0.5, lacunarity ~2), about [-1, 1]. */
inline float fbm2(float x, float y, int octaves, uint32_t seed)
{
	float sum = 0, amp = 1, norm = 0;
	for (int o = 0; o < octaves; o++)
	{
		sum += amp * valueNoise2(x, y, seed + 0x9e37U * static_cast<uint32_t>(o));
		norm += amp;
		amp *= 0.5f;
		// 2.03 rather than 2 so that octave lattices do not line up.
		x *= 2.03f;
		y *= 2.03f;
	}
	return sum / norm;
}

/** Fractal sum of 3D value noise, about [-1, 1]. */
inline float fbm3(float x, float y, float z, int octaves, uint32_t seed)
{
	float sum = 0, amp = 1, norm = 0;
	for (int o = 0; o < octaves; o++)
	{
		sum += amp * valueNoise3(x, y, z, seed + 0x9e37U * static_cast<uint32_t>(o));
		norm += amp;
		amp *= 0.5f;
		x *= 2.03f;
		y *= 2.03f;
		z *= 2.03f;
	}
	return sum / norm;
}

/** splitmix64: tiny, fast, well-mixed; reproducible across platforms
 * (std:: distributions are not). */
class SplitMix64
{
   public:
	explicit SplitMix64(uint64_t seed) : m_state(seed) {}
	uint64_t next()
	{
		uint64_t z = (m_state += 0x9e3779b97f4a7c15ULL);
		z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
		z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
		return z ^ (z >> 31);
	}
	/** Uniform in [0, 1). */
	double uniform() { return static_cast<double>(next() >> 11) * (1.0 / 9007199254740992.0); }
	double uniform(double a, double b) { return a + (b - a) * uniform(); }
	/** Standard normal (Box-Muller). */
	double normal()
	{
		const double u1 = 1.0 - uniform(), u2 = uniform();
		return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
	}

   private:
	uint64_t m_state;
};

}  // namespace shadyloc::sim
