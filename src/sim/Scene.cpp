/* ShadyLoc simulator — the world, its textures and the ray caster. */
#include <shadyloc/sim/Noise.h>
#include <shadyloc/sim/Scene.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace shadyloc::sim
{
namespace
{
constexpr float kEps = 1e-3f;

/** Mailbox: a primitive spanning several grid cells is tested once per ray.
 * Per thread, stamped with a ray counter, so no clearing between rays. */
struct Mailbox
{
	std::vector<uint32_t> stamp;
	uint32_t ray = 0;
	void next(size_t n)
	{
		if (stamp.size() != n) stamp.assign(n, 0), ray = 0;
		if (++ray == 0) std::fill(stamp.begin(), stamp.end(), 0), ray = 1;
	}
	bool seen(uint32_t i)
	{
		if (stamp[i] == ray) return true;
		stamp[i] = ray;
		return false;
	}
};
thread_local Mailbox tlMailbox;
constexpr float kInf = std::numeric_limits<float>::infinity();

float smoothstep(float a, float b, float x)
{
	const float t = std::clamp((x - a) / (b - a), 0.0f, 1.0f);
	return t * t * (3 - 2 * t);
}

/** Procedural texture of one material: a brightness field (fractal noise
 * plus a fine grain) and a chromatic field (which basis spectrum). */
struct TexSpec
{
	float scale;  //!< coarsest brightness feature (m)
	float contrast;	 //!< brightness amplitude
	int octaves;
	float fine;	 //!< grain size (m)
	float fineContrast;
	float mixScale;	 //!< chromatic feature size (m)
	float mixContrast;
};
// Indexed by Material. Sizes chosen so that VO finds corners at the ranges
// the camera sees each material (asphalt and grass 3-30 m, walls 5-40 m).
const TexSpec kTex[kMaterialCount] = {
	{1, 0, 1, 1, 0, 1, 0},	// sky (unused)
	{1.6f, 0.22f, 4, 0.05f, 0.18f, 2.5f, 0.7f},	 // asphalt
	{0.6f, 0.10f, 2, 0.05f, 0.08f, 1.5f, 0.6f},	 // paint
	{1.2f, 0.12f, 3, 0.04f, 0.10f, 3.0f, 0.5f},	 // paving (slabs added on top)
	{0.9f, 0.35f, 4, 0.06f, 0.25f, 2.5f, 0.9f},	 // grass
	{2.0f, 0.10f, 2, 0.03f, 0.08f, 3.0f, 0.5f},	 // brick (bricks added on top)
	{1.4f, 0.14f, 4, 0.04f, 0.08f, 4.0f, 0.8f},	 // render
	{0.8f, 0.18f, 4, 0.04f, 0.12f, 2.0f, 0.6f},	 // concrete
	{0.8f, 0.20f, 2, 0.05f, 0.05f, 1.0f, 0.8f},	 // glass
	{0.25f, 0.35f, 3, 0.03f, 0.15f, 0.6f, 0.8f},  // bark
	{0.5f, 0.45f, 3, 0.05f, 0.20f, 1.5f, 0.9f},	 // foliage
	{1, 0, 1, 1, 0, 1, 0},	// marker: flat, to be found by colour
};

/** Number of octaves whose finest feature is still >= 1.5 pixel footprints:
 * band-limiting by construction instead of supersampling. */
int octavesFor(float scale, int maxOct, float lod)
{
	int n = 0;
	float s = scale;
	while (n < maxOct && s >= 1.5f * lod)
	{
		n++;
		s *= 0.4926f;  // 1 / 2.03, the fbm lacunarity
	}
	return std::max(n, 1);
}

void texture2(int m, float u, float v, float lod, uint32_t seed, const TSimSceneOptions& o,
	float& brightness, float& mix)
{
	const TexSpec& t = kTex[m];
	const float tc = static_cast<float>(o.texture_contrast);
	const int oct = octavesFor(t.scale, t.octaves, lod);
	float b = t.contrast * fbm2(u / t.scale, v / t.scale, oct, seed);
	const float fineFade = smoothstep(1.5f * lod, 3.0f * lod, t.fine);
	if (fineFade > 0) b += fineFade * t.fineContrast * valueNoise2(u / t.fine, v / t.fine, seed ^ 0x51edU);
	brightness = std::max(0.15f, 1.0f + tc * b);
	mix = std::clamp(
		0.5f + static_cast<float>(o.texture_chroma) * t.mixContrast *
				   fbm2(u / t.mixScale + 17.3f, v / t.mixScale - 5.1f, 2, seed ^ 0xc0ffeeU) * 1.4f,
		0.0f, 1.0f);
}

void texture3(int m, const V3& p, float lod, uint32_t seed, const TSimSceneOptions& o, float& brightness,
	float& mix)
{
	const TexSpec& t = kTex[m];
	const float tc = static_cast<float>(o.texture_contrast);
	const int oct = octavesFor(t.scale, t.octaves, lod);
	const float b = t.contrast * fbm3(p.x / t.scale, p.y / t.scale, p.z / t.scale, oct, seed);
	brightness = std::max(0.15f, 1.0f + tc * b);
	mix = std::clamp(
		0.5f + static_cast<float>(o.texture_chroma) * t.mixContrast *
				   fbm3(p.x / t.mixScale, p.y / t.mixScale, p.z / t.mixScale, 2, seed ^ 0xc0ffeeU) * 1.4f,
		0.0f, 1.0f);
}

/** Running-bond brick courses on a wall (u along the wall, v up, m). */
void brickPattern(float u, float v, float lod, uint32_t seed, const TSimSceneOptions& o, float& brightness,
	float& mix)
{
	constexpr float kLen = 0.225f, kCourse = 0.075f;
	float bBase, mBase;
	texture2(kBrick, u, v, lod, seed, o, bBase, mBase);
	const float tc = static_cast<float>(o.texture_contrast), ch = static_cast<float>(o.texture_chroma);
	if (lod > 0.6f * kCourse)
	{
		// Bricks below the pixel size: their average (18% mortar).
		brightness = bBase;
		mix = std::clamp(0.18f + 0.3f * ch * (mBase - 0.5f), 0.0f, 1.0f);
		return;
	}
	const float row = std::floor(v / kCourse);
	const float uu = u / kLen + 0.5f * (static_cast<int>(row) & 1);
	const float col = std::floor(uu);
	const float fu = uu - col, fv = v / kCourse - row;
	if (fu < 0.045f || fv < 0.13f)
	{
		brightness = bBase * (1.0f + 0.1f * tc);
		mix = 1.0f;	 // mortar
		return;
	}
	const uint32_t h = hashLattice(static_cast<int>(col), static_cast<int>(row), 7, seed);
	brightness = std::max(0.15f, bBase * (1.0f + tc * 0.22f * hashToSigned(h)));
	mix = std::clamp(ch * 0.35f * (0.5f + 0.5f * hashToSigned(hash32(h))), 0.0f, 0.9f);
}

/** Square slabs (s, d in m) with dark joints and per-slab tone. */
void slabPattern(float s, float d, float lod, uint32_t seed, const TSimSceneOptions& o, float& brightness,
	float& mix)
{
	constexpr float kSlab = 0.6f;
	float bBase, mBase;
	texture2(kPaving, s, d, lod, seed, o, bBase, mBase);
	if (lod > 0.25f * kSlab)
	{
		brightness = bBase * 0.95f;
		mix = mBase;
		return;
	}
	const float a = s / kSlab, b = d / kSlab;
	const float ia = std::floor(a), ib = std::floor(b);
	const float fa = a - ia, fb = b - ib;
	const float tc = static_cast<float>(o.texture_contrast);
	if (fa < 0.03f || fb < 0.03f)
	{
		brightness = bBase * (1.0f - 0.45f * tc);
		mix = mBase;
		return;
	}
	const uint32_t h = hashLattice(static_cast<int>(ia), static_cast<int>(ib), 3, seed);
	brightness = std::max(0.15f, bBase * (1.0f + tc * 0.15f * hashToSigned(h)));
	// One slab in five is of the reddish kind.
	mix = (h >> 29) == 0 ? std::min(1.0f, mBase + 0.5f * static_cast<float>(o.texture_chroma)) : mBase * 0.6f;
}

bool hitBox(const Primitive& b, const V3& o, const V3& d, float tmin, float tmax, float& t, V3& n)
{
	const V3 q = o - b.c;
	const float lo[3] = {b.cosYaw * q.x + b.sinYaw * q.y, -b.sinYaw * q.x + b.cosYaw * q.y, q.z};
	const float ld[3] = {b.cosYaw * d.x + b.sinYaw * d.y, -b.sinYaw * d.x + b.cosYaw * d.y, d.z};
	const float hs[3] = {b.h.x, b.h.y, b.h.z};
	float tn = -kInf, tf = kInf;
	int axis = 0;
	for (int k = 0; k < 3; k++)
	{
		if (std::abs(ld[k]) < 1e-9f)
		{
			if (std::abs(lo[k]) > hs[k]) return false;
			continue;
		}
		float t1 = (-hs[k] - lo[k]) / ld[k], t2 = (hs[k] - lo[k]) / ld[k];
		if (t1 > t2) std::swap(t1, t2);
		if (t1 > tn)
		{
			tn = t1;
			axis = k;
		}
		tf = std::min(tf, t2);
		if (tn > tf) return false;
	}
	if (tn <= tmin || tn >= tmax) return false;	 // behind, inside, or farther than the best
	t = tn;
	float ln[3] = {0, 0, 0};
	ln[axis] = ld[axis] > 0 ? -1.0f : 1.0f;
	n = V3(b.cosYaw * ln[0] - b.sinYaw * ln[1], b.sinYaw * ln[0] + b.cosYaw * ln[1], ln[2]);
	return true;
}

bool hitCylinder(const Primitive& c, const V3& o, const V3& d, float tmin, float tmax, float& t, V3& n)
{
	const float ox = o.x - c.c.x, oy = o.y - c.c.y, r = c.h.x, top = c.c.z + c.h.z;
	const float a = d.x * d.x + d.y * d.y;
	if (a > 1e-12f)
	{
		const float b = ox * d.x + oy * d.y, cc = ox * ox + oy * oy - r * r;
		const float disc = b * b - a * cc;
		if (disc < 0) return false;
		const float tt = (-b - std::sqrt(disc)) / a;
		if (tt > tmin && tt < tmax)
		{
			const float z = o.z + tt * d.z;
			if (z >= c.c.z && z <= top)
			{
				t = tt;
				n = V3((ox + tt * d.x) / r, (oy + tt * d.y) / r, 0);
				return true;
			}
		}
	}
	if (d.z < 0 && o.z > top)  // the top cap, seen from above
	{
		const float tt = (top - o.z) / d.z;
		const float px = ox + tt * d.x, py = oy + tt * d.y;
		if (tt > tmin && tt < tmax && px * px + py * py <= r * r)
		{
			t = tt;
			n = V3(0, 0, 1);
			return true;
		}
	}
	return false;
}

/** Both roots of a ray against an ellipsoid; false if it misses. */
bool ellipsoidChord(const Primitive& e, const V3& o, const V3& d, float& t0, float& t1)
{
	const V3 q((o.x - e.c.x) / e.h.x, (o.y - e.c.y) / e.h.y, (o.z - e.c.z) / e.h.z);
	const V3 k(d.x / e.h.x, d.y / e.h.y, d.z / e.h.z);
	const float a = k.dot(k), b = q.dot(k), c = q.dot(q) - 1.0f;
	const float disc = b * b - a * c;
	if (disc < 0) return false;
	const float sq = std::sqrt(disc);
	t0 = (-b - sq) / a;
	t1 = (-b + sq) / a;
	return true;
}

V3 ellipsoidNormal(const Primitive& e, const V3& p)
{
	return V3((p.x - e.c.x) / (e.h.x * e.h.x), (p.y - e.c.y) / (e.h.y * e.h.y),
		(p.z - e.c.z) / (e.h.z * e.h.z))
		.normalized();
}

/** Deterministic uniform numbers for the layout. */
struct LayoutRng
{
	SplitMix64 g;
	explicit LayoutRng(uint32_t seed) : g(0x5eed0000ULL ^ seed) {}
	float u(float a, float b) { return static_cast<float>(g.uniform(a, b)); }
	bool chance(double p) { return g.uniform() < p; }
	uint32_t id() { return static_cast<uint32_t>(g.next()); }
};
}  // namespace

// ------------------------------------------------------------------ materials
const char* materialName(int m)
{
	static const char* names[kMaterialCount] = {"sky",	"asphalt", "paint", "paving", "grass", "brick",
												"render", "concrete", "glass", "bark", "foliage", "marker"};
	return (m >= 0 && m < kMaterialCount) ? names[m] : "?";
}

ReflectanceModel materialReflectance(int m, int j)
{
	// Smooth curves shaped after published field spectra (ASTER/ECOSTRESS
	// library: asphalt, grass, red brick, concrete), simplified to a few terms.
	using L = ReflectanceModel::Lobe;
	ReflectanceModel r;
	const bool a = (j == 0);
	switch (m)
	{
		case kAsphalt:
			r.base = a ? 0.07 : 0.10;
			if (a) r.steps = {L{600, 40, 0.04}};
			else r.lobes = {L{450, 40, 0.025}};
			break;
		case kPaint:
			r.base = a ? 0.62 : 0.35;
			r.steps = {a ? L{450, 15, 0.12} : L{520, 25, 0.28}};
			break;
		case kPaving:
			r.base = a ? 0.17 : 0.11;
			r.steps = {a ? L{580, 40, 0.07} : L{590, 25, 0.20}};
			break;
		case kGrass:
			r.base = a ? 0.03 : 0.05;
			if (a)
			{
				r.lobes = {L{550, 30, 0.10}};
				r.steps = {L{695, 8, 0.35}};
			}
			else
				r.steps = {L{540, 30, 0.20}};
			break;
		case kBrick:
			r.base = a ? 0.06 : 0.33;
			r.steps = {a ? L{590, 18, 0.30} : L{550, 60, 0.08}};
			break;
		case kRender:
			r.base = a ? 0.40 : 0.33;
			if (a) r.steps = {L{500, 30, 0.18}};
			else r.lobes = {L{460, 40, 0.14}};
			break;
		case kConcrete:
			r.base = a ? 0.27 : 0.22;
			r.steps = {a ? L{550, 80, 0.05} : L{560, 40, 0.09}};
			break;
		case kGlass:
			r.base = a ? 0.04 : 0.06;
			if (a) r.lobes = {L{470, 50, 0.03}};
			break;
		case kBark:
			r.base = a ? 0.05 : 0.09;
			r.steps = {a ? L{600, 40, 0.08} : L{560, 50, 0.05}};
			break;
		case kFoliage:
			r.base = a ? 0.04 : 0.05;
			if (a)
			{
				r.lobes = {L{550, 28, 0.12}};
				r.steps = {L{695, 8, 0.30}};
			}
			else
				r.lobes = {L{565, 35, 0.18}};
			break;
		case kMarker:
			r.base = 0.04;
			r.lobes = {L{440, 25, 0.60}};
			r.steps = {L{625, 12, 0.70}};
			break;
		default: r.base = 1.0;	// sky: a white "reflector" for the sky radiance
	}
	return r;
}

// ------------------------------------------------------------------ route
Route::Route(double length, double amplitude, double phase)
	: m_length(length), m_A(amplitude), m_k(2 * M_PI / length), m_phase(phase)
{
	m_x0 = -0.5 * length - 200;
	const double x1 = 1.5 * length + 200;
	const size_t n = static_cast<size_t>((x1 - m_x0) / m_dx) + 1;
	m_s.resize(n);
	double s = 0;
	for (size_t i = 0; i < n; i++)
	{
		if (i > 0)
		{
			const double xm = m_x0 + (i - 0.5) * m_dx;	// midpoint rule
			s += m_dx * std::sqrt(1 + slope(xm) * slope(xm));
		}
		m_s[i] = s;
	}
	const double s0 = sAt(0.0);
	for (auto& v : m_s) v -= s0;
}

double Route::sAt(double x) const
{
	const double f = (x - m_x0) / m_dx;
	const size_t i = static_cast<size_t>(std::clamp(f, 0.0, static_cast<double>(m_s.size() - 2)));
	const double w = f - static_cast<double>(i);
	return m_s[i] + w * (m_s[i + 1] - m_s[i]);
}

double Route::xAt(double s) const
{
	const auto it = std::lower_bound(m_s.begin(), m_s.end(), s);
	size_t i = static_cast<size_t>(it - m_s.begin());
	i = std::clamp<size_t>(i, 1, m_s.size() - 1);
	const double w = (s - m_s[i - 1]) / (m_s[i] - m_s[i - 1]);
	return m_x0 + m_dx * (static_cast<double>(i - 1) + w);
}

void Route::pointAt(double s, double d, double& x, double& y, double& heading) const
{
	const double xc = xAt(s);
	heading = std::atan(slope(xc));
	x = xc - std::sin(heading) * d;
	y = centreY(xc) + std::cos(heading) * d;
}

void Route::coords(float x, float y, float& s, float& d) const
{
	const double m = slope(x);
	const double dd = (y - centreY(x)) / std::sqrt(1 + m * m);
	// Move to the foot of the normal before reading the arc length.
	const double xf = x + m * dd / std::sqrt(1 + m * m);
	d = static_cast<float>(dd);
	s = static_cast<float>(sAt(xf));
}

// ------------------------------------------------------------------ layout
Scene::Scene(const TSimSceneOptions& opts) : m_opts(opts)
{
	m_opts.validate();
	LayoutRng rng(m_opts.seed);
	m_route = Route(m_opts.route_length_m, m_opts.route_amplitude_m, rng.u(0, 2 * M_PI));
	// Leaf threshold: the canopy_gap_fraction quantile of the leaf noise.
	std::vector<float> v(8192);
	SplitMix64 g(12345);
	for (auto& x : v)
		x = valueNoise3(
			static_cast<float>(g.uniform(-500, 500)), static_cast<float>(g.uniform(-500, 500)),
			static_cast<float>(g.uniform(-500, 500)), 99);
	std::sort(v.begin(), v.end());
	const double f = std::clamp(m_opts.canopy_gap_fraction, 0.0, 1.0);
	m_leafThreshold = f <= 0 ? -2.0f : f >= 1 ? 2.0f : v[static_cast<size_t>(f * (v.size() - 1))];
	layout();
	build();
}

void Scene::add(const Primitive& p0)
{
	Primitive p = p0;
	switch (p.type)
	{
		case Primitive::Box:
		{
			const float ex = std::abs(p.cosYaw) * p.h.x + std::abs(p.sinYaw) * p.h.y;
			const float ey = std::abs(p.sinYaw) * p.h.x + std::abs(p.cosYaw) * p.h.y;
			p.bx0 = p.c.x - ex, p.bx1 = p.c.x + ex, p.by0 = p.c.y - ey, p.by1 = p.c.y + ey;
			p.zTop = p.c.z + p.h.z;
			break;
		}
		case Primitive::Cylinder:
			p.bx0 = p.c.x - p.h.x, p.bx1 = p.c.x + p.h.x, p.by0 = p.c.y - p.h.x, p.by1 = p.c.y + p.h.x;
			p.zTop = p.c.z + p.h.z;
			break;
		case Primitive::Ellipsoid:
			p.bx0 = p.c.x - p.h.x, p.bx1 = p.c.x + p.h.x, p.by0 = p.c.y - p.h.y, p.by1 = p.c.y + p.h.y;
			p.zTop = p.c.z + p.h.z;
			break;
	}
	m_prims.push_back(p);
}

void Scene::layout()
{
	LayoutRng rng(m_opts.seed * 7919u + 1u);
	const float rh = static_cast<float>(m_opts.road_half_width_m);
	const float sw = static_cast<float>(m_opts.sidewalk_width_m);
	const float L = static_cast<float>(m_opts.route_length_m);
	const float treesEnd = static_cast<float>(m_opts.trees_end_m);
	const float bEnd = static_cast<float>(m_opts.buildings_end_m);
	// Scenery from 40 m before the route to 60 m past it: a traversal may end
	// kEndMargin_m past the route and still see 40 m of it ahead.
	const float sBegin = -40.0f, sEnd = L + static_cast<float>(TSimSceneOptions::kEndMargin_m) + 40.0f;

	auto at = [&](float s, float d, float& x, float& y, float& hd) {
		double xx, yy, hh;
		m_route.pointAt(s, d, xx, yy, hh);
		x = static_cast<float>(xx), y = static_cast<float>(yy), hd = static_cast<float>(hh);
	};
	auto box = [&](float s, float d, float len, float depth, float height, uint8_t mat, bool win,
				   float z0 = 0) {
		Primitive p;
		float x, y, hd;
		at(s, d, x, y, hd);
		p.type = Primitive::Box;
		p.material = mat;
		p.windows = win;
		p.c = V3(x, y, z0 + 0.5f * height);
		p.h = V3(0.5f * len, 0.5f * depth, 0.5f * height);
		p.cosYaw = std::cos(hd), p.sinYaw = std::sin(hd);
		p.seed = rng.id();
		add(p);
	};
	auto cylinder = [&](float s, float d, float r, float height, uint8_t mat) {
		Primitive p;
		float x, y, hd;
		at(s, d, x, y, hd);
		p.type = Primitive::Cylinder;
		p.material = mat;
		p.c = V3(x, y, 0);
		p.h = V3(r, r, height);
		p.seed = rng.id();
		add(p);
	};
	auto canopy = [&](float s, float d, float z, float rx, float ry, float rz) {
		Primitive p;
		float x, y, hd;
		at(s, d, x, y, hd);
		p.type = Primitive::Ellipsoid;
		p.material = kFoliage;
		p.canopy = true;
		p.c = V3(x, y, z);
		p.h = V3(rx, ry, rz);
		p.seed = rng.id();
		add(p);
	};
	auto tree = [&](float s, float d, float scale) {
		const float zc = scale * rng.u(5.0f, 6.8f), rx = scale * rng.u(2.8f, 3.8f);
		const float rz = scale * rng.u(2.2f, 3.0f);
		cylinder(s, d, scale * rng.u(0.18f, 0.32f), zc - 0.3f * rz, kBark);
		canopy(s, d, zc, rx, rx * rng.u(0.9f, 1.1f), rz);
	};

	const float kerb = rh + sw;
	for (int side : {-1, 1})
	{
		const float sg = static_cast<float>(side);
		// Tree-lined avenue: a row at the kerb, a second row and hedges behind.
		for (float s = sBegin + rng.u(0, 4); s < treesEnd; s += static_cast<float>(m_opts.tree_spacing_m) * rng.u(0.75f, 1.25f))
		{
			tree(s, sg * (kerb + rng.u(0.8f, 1.8f)), 1.0f);
			if (rng.chance(0.6)) tree(s + rng.u(-2, 2), sg * (kerb + rng.u(8, 13)), rng.u(1.0f, 1.3f));
			if (rng.chance(0.5))
				box(s + 4, sg * (kerb + 4.5f), rng.u(3, 6), 1.0f, rng.u(0.9f, 1.5f), kFoliage, false);
		}
		// Buildings: a street canyon of brick and rendered facades with windows.
		for (float s = treesEnd + rng.u(0, 3); s < bEnd;)
		{
			const float len = rng.u(10, 24), depth = rng.u(8, 14), height = rng.u(5, 16);
			const float setback = rng.u(0.5f, 3.0f);
			box(s + 0.5f * len, sg * (kerb + setback + 0.5f * depth), len, depth, height,
				rng.chance(0.5) ? kBrick : kRender, true);
			s += len + (rng.chance(0.2) ? rng.u(8, 15) : rng.u(1.5f, 6));
		}
		// Open stretch: garden walls, bushes, the odd tree.
		for (float s = bEnd + rng.u(0, 3); s < sEnd;)
		{
			const float len = rng.u(4, 12);
			if (rng.chance(0.7))
				box(s + 0.5f * len, sg * (kerb + rng.u(1, 3)), len, 0.3f, rng.u(0.7f, 1.5f),
					rng.chance(0.5) ? kBrick : kConcrete, false);
			if (rng.chance(0.35))
			{
				const float r = rng.u(0.8f, 1.5f);
				canopy(s + rng.u(0, len), sg * (kerb + rng.u(4, 8)), 0.7f * r, r, r * rng.u(0.8f, 1.2f), 0.8f * r);
			}
			if (rng.chance(0.15)) tree(s + rng.u(0, len), sg * (kerb + rng.u(5, 10)), rng.u(0.9f, 1.3f));
			s += len + rng.u(1, 5);
		}
		// Far background all along: large buildings, structure at depth.
		for (float s = sBegin + rng.u(0, 20); s < sEnd + 80; s += rng.u(25, 50))
			if (rng.chance(0.7))
				box(s, sg * rng.u(30, 55), rng.u(15, 30), rng.u(8, 14), rng.u(8, 22),
					rng.chance(0.5) ? kBrick : kRender, true);
		// Lamp posts.
		for (float s = sBegin + (side > 0 ? 0 : 15); s < sEnd; s += 30)
		{
			cylinder(s, sg * (rh + 0.45f), 0.08f, 5.5f, kConcrete);
			box(s, sg * (rh + 0.1f), 0.25f, 0.9f, 0.15f, kConcrete, false, 5.45f);
		}
	}
	for (const auto& m : m_opts.markers)
	{
		Primitive p;
		p.type = Primitive::Ellipsoid;
		p.material = kMarker;
		p.c = V3(static_cast<float>(m[0]), static_cast<float>(m[1]), static_cast<float>(m[2]));
		p.h = V3(static_cast<float>(m[3]), static_cast<float>(m[3]), static_cast<float>(m[3]));
		add(p);
	}
}

void Scene::build()
{
	float x0 = -50, x1 = 50, y0 = -50, y1 = 50;
	m_zTop = 0.1f;
	for (const auto& p : m_prims)
	{
		x0 = std::min(x0, p.bx0), x1 = std::max(x1, p.bx1);
		y0 = std::min(y0, p.by0), y1 = std::max(y1, p.by1);
		m_zTop = std::max(m_zTop, p.zTop);
	}
	m_gx0 = x0 - 1, m_gy0 = y0 - 1;
	m_nx = static_cast<int>(std::ceil((x1 + 1 - m_gx0) / m_cell));
	m_ny = static_cast<int>(std::ceil((y1 + 1 - m_gy0) / m_cell));
	const size_t nc = static_cast<size_t>(m_nx) * static_cast<size_t>(m_ny);
	std::vector<uint32_t> count(nc + 1, 0);
	auto cellRange = [&](const Primitive& p, int& i0, int& i1, int& j0, int& j1) {
		i0 = std::clamp(static_cast<int>((p.bx0 - m_gx0) / m_cell), 0, m_nx - 1);
		i1 = std::clamp(static_cast<int>((p.bx1 - m_gx0) / m_cell), 0, m_nx - 1);
		j0 = std::clamp(static_cast<int>((p.by0 - m_gy0) / m_cell), 0, m_ny - 1);
		j1 = std::clamp(static_cast<int>((p.by1 - m_gy0) / m_cell), 0, m_ny - 1);
	};
	for (const auto& p : m_prims)
	{
		int i0, i1, j0, j1;
		cellRange(p, i0, i1, j0, j1);
		for (int j = j0; j <= j1; j++)
			for (int i = i0; i <= i1; i++) count[static_cast<size_t>(j) * m_nx + i + 1]++;
	}
	for (size_t c = 0; c < nc; c++) count[c + 1] += count[c];
	m_cellStart = count;
	m_cellItems.assign(count[nc], 0);
	std::vector<uint32_t> fill(count.begin(), count.end() - 1);
	for (size_t k = 0; k < m_prims.size(); k++)
	{
		int i0, i1, j0, j1;
		cellRange(m_prims[k], i0, i1, j0, j1);
		for (int j = j0; j <= j1; j++)
			for (int i = i0; i <= i1; i++)
				m_cellItems[fill[static_cast<size_t>(j) * m_nx + i]++] = static_cast<uint32_t>(k);
	}
}

// ------------------------------------------------------------------ casting
template <class Visit>
void Scene::walk(const V3& o, const V3& d, float tmax, Visit&& visit) const
{
	float t0 = 0, t1 = tmax;
	if (d.z > 1e-7f)
	{
		if (o.z > m_zTop) return;
		t1 = std::min(t1, (m_zTop - o.z) / d.z);
	}
	else if (d.z < -1e-7f)
	{
		if (o.z > m_zTop) t0 = std::max(t0, (m_zTop - o.z) / d.z);
	}
	else if (o.z > m_zTop)
		return;
	const float gx1 = m_gx0 + m_nx * m_cell, gy1 = m_gy0 + m_ny * m_cell;
	const float oc[2] = {o.x, o.y}, dc[2] = {d.x, d.y}, lo[2] = {m_gx0, m_gy0}, hi[2] = {gx1, gy1};
	for (int k = 0; k < 2; k++)
	{
		if (std::abs(dc[k]) < 1e-9f)
		{
			if (oc[k] < lo[k] || oc[k] > hi[k]) return;
			continue;
		}
		float ta = (lo[k] - oc[k]) / dc[k], tb = (hi[k] - oc[k]) / dc[k];
		if (ta > tb) std::swap(ta, tb);
		t0 = std::max(t0, ta), t1 = std::min(t1, tb);
	}
	if (t0 > t1) return;
	const float px = o.x + d.x * t0, py = o.y + d.y * t0;
	int ix = std::clamp(static_cast<int>((px - m_gx0) / m_cell), 0, m_nx - 1);
	int iy = std::clamp(static_cast<int>((py - m_gy0) / m_cell), 0, m_ny - 1);
	const int sx = d.x > 0 ? 1 : -1, sy = d.y > 0 ? 1 : -1;
	const float tdx = std::abs(d.x) > 1e-9f ? m_cell / std::abs(d.x) : kInf;
	const float tdy = std::abs(d.y) > 1e-9f ? m_cell / std::abs(d.y) : kInf;
	float tmx = std::abs(d.x) > 1e-9f ? (m_gx0 + (ix + (d.x > 0)) * m_cell - o.x) / d.x : kInf;
	float tmy = std::abs(d.y) > 1e-9f ? (m_gy0 + (iy + (d.y > 0)) * m_cell - o.y) / d.y : kInf;
	for (;;)
	{
		const float exitT = std::min(tmx, tmy);
		const size_t c = static_cast<size_t>(iy) * m_nx + ix;
		if (m_cellStart[c] != m_cellStart[c + 1] &&
			visit(m_cellStart[c], m_cellStart[c + 1], std::min(exitT, t1)))
			return;
		if (exitT >= t1) return;
		if (tmx < tmy)
		{
			ix += sx;
			if (ix < 0 || ix >= m_nx) return;
			tmx += tdx;
		}
		else
		{
			iy += sy;
			if (iy < 0 || iy >= m_ny) return;
			tmy += tdy;
		}
	}
}

float Scene::leafCover(const Primitive& pr, const V3& p, const V3& w) const
{
	const float inv = 1.0f / static_cast<float>(m_opts.leaf_scale_m);
	// One octave: leaf clumps and gaps of about leaf_scale_m.
	const float n = valueNoise3((p.x + w.x) * inv, (p.y + w.y) * inv, (p.z + w.z) * inv, pr.seed);
	return smoothstep(m_leafThreshold - 0.05f, m_leafThreshold + 0.05f, n);
}

V3 Scene::windOffset(uint32_t windSeed) const
{
	if (windSeed == 0) return V3();
	SplitMix64 g(0xa11ce000ULL + windSeed);
	const float a = static_cast<float>(m_opts.canopy_wind_m);
	return V3(static_cast<float>(g.uniform(-a, a)), static_cast<float>(g.uniform(-a, a)),
		static_cast<float>(g.uniform(-a, a)));
}

void Scene::groundSurface(const V3& p, float lod, SurfaceHit& hit) const
{
	float s, d;
	m_route.coords(p.x, p.y, s, d);
	const float ad = std::abs(d);
	const float rh = static_cast<float>(m_opts.road_half_width_m);
	const float sw = static_cast<float>(m_opts.sidewalk_width_m);
	const bool inBuildings = s > m_opts.trees_end_m && s < m_opts.buildings_end_m;
	hit.n = V3(0, 0, 1);
	const uint32_t seed = m_opts.seed * 31u + 11u;
	if (ad < rh)
	{
		const bool centreDash = ad < 0.07f && std::fmod(s + 9000.0f, 9.0f) < 3.0f;
		const bool edge = ad > rh - 0.32f && ad < rh - 0.2f;
		hit.material = (centreDash || edge) ? kPaint : kAsphalt;
		texture2(hit.material, p.x, p.y, lod, seed, m_opts, hit.brightness, hit.mix);
	}
	else if (ad < rh + 0.2f)
	{
		hit.material = kConcrete;  // kerb
		texture2(kConcrete, s, d, lod, seed, m_opts, hit.brightness, hit.mix);
	}
	else if (ad < rh + sw || (inBuildings && ad < rh + sw + 6))
	{
		hit.material = kPaving;
		slabPattern(s, d, lod, seed, m_opts, hit.brightness, hit.mix);
	}
	else
	{
		hit.material = kGrass;
		texture2(kGrass, p.x, p.y, lod, seed, m_opts, hit.brightness, hit.mix);
	}
}

void Scene::surfaceOf(const Primitive& pr, float lod, const V3& wind, SurfaceHit& hit) const
{
	hit.material = pr.material;
	const V3& p = hit.p;
	switch (pr.type)
	{
		case Primitive::Box:
		{
			const V3 q = p - pr.c;
			const float lx = pr.cosYaw * q.x + pr.sinYaw * q.y, ly = -pr.sinYaw * q.x + pr.cosYaw * q.y;
			const float nlx = pr.cosYaw * hit.n.x + pr.sinYaw * hit.n.y;
			const float nly = -pr.sinYaw * hit.n.x + pr.cosYaw * hit.n.y;
			if (std::abs(hit.n.z) > 0.5f)
			{
				texture2(kConcrete, lx, ly, lod, pr.seed, m_opts, hit.brightness, hit.mix);
				hit.material = kConcrete;  // roofs and wall tops
				break;
			}
			const bool alongX = std::abs(nly) > std::abs(nlx);	// face normal along local y
			const float u = (alongX ? lx + pr.h.x : ly + pr.h.y) + (nlx + nly > 0 ? 0.0f : 100.0f);
			const float v = q.z + pr.h.z;  // height above the box base
			if (pr.windows && v > 0.8f && v < 2 * pr.h.z - 0.8f)
			{
				// Window grid: 3 m bays, 3.2 m storeys, 1.3 x 1.6 m panes.
				const float bu = std::fmod(u + 200.0f, 3.0f), fl = std::fmod(v, 3.2f);
				const float faceLen = alongX ? 2 * pr.h.x : 2 * pr.h.y;
				const float uu = alongX ? lx + pr.h.x : ly + pr.h.y;
				if (bu > 0.85f && bu < 2.15f && fl > 0.9f && fl < 2.5f && uu > 1.0f && uu < faceLen - 1.0f)
				{
					hit.material = kGlass;
					texture2(kGlass, u, v, lod, pr.seed, m_opts, hit.brightness, hit.mix);
					break;
				}
			}
			if (pr.material == kBrick)
				brickPattern(u, v, lod, pr.seed, m_opts, hit.brightness, hit.mix);
			else
				texture2(pr.material, u, v, lod, pr.seed, m_opts, hit.brightness, hit.mix);
			break;
		}
		case Primitive::Cylinder:
		{
			const float a = std::atan2(p.y - pr.c.y, p.x - pr.c.x) * pr.h.x;
			texture2(pr.material, a, p.z, lod, pr.seed, m_opts, hit.brightness, hit.mix);
			break;
		}
		case Primitive::Ellipsoid:
			if (pr.material == kMarker)
			{
				hit.brightness = 1, hit.mix = 0;
				break;
			}
			texture3(pr.material, p + wind, lod, pr.seed, m_opts, hit.brightness, hit.mix);
			break;
	}
}

bool Scene::intersect(const V3& o, const V3& d, float tmax, float footprint, const V3& wind,
	SurfaceHit& hit) const
{
	float best = tmax;
	int bestPrim = -1;
	bool ground = false;
	V3 bestN;
	if (d.z < -1e-6f)
	{
		const float tg = -o.z / d.z;
		if (tg > 0 && tg < best)
		{
			best = tg;
			ground = true;
		}
	}
	Mailbox& mb = tlMailbox;
	mb.next(m_prims.size());
	walk(o, d, best, [&](uint32_t first, uint32_t last, float exitT) {
		for (uint32_t k = first; k < last; k++)
		{
			const uint32_t i = m_cellItems[k];
			if (mb.seen(i)) continue;
			const Primitive& pr = m_prims[i];
			float t;
			V3 n;
			bool h = false;
			switch (pr.type)
			{
				case Primitive::Box: h = hitBox(pr, o, d, kEps, best, t, n); break;
				case Primitive::Cylinder: h = hitCylinder(pr, o, d, kEps, best, t, n); break;
				case Primitive::Ellipsoid:
				{
					float t0, t1;
					if (!ellipsoidChord(pr, o, d, t0, t1) || t1 <= kEps || t0 >= best) break;
					if (!pr.canopy)
					{
						if (t0 > kEps)
						{
							t = t0;
							n = ellipsoidNormal(pr, o + d * t0);
							h = true;
						}
						break;
					}
					// Leafy canopy: a gap in the near side shows the far side;
					// gaps in both let the ray through.
					if (t0 > kEps && leafCover(pr, o + d * t0, wind) > 0.5f)
					{
						t = t0;
						n = ellipsoidNormal(pr, o + d * t0);
						h = true;
					}
					else if (t1 < best && leafCover(pr, o + d * t1, wind) > 0.5f)
					{
						t = t1;
						n = -ellipsoidNormal(pr, o + d * t1);
						h = true;
					}
					break;
				}
			}
			if (h && t < best)
			{
				best = t;
				bestPrim = static_cast<int>(i);
				bestN = n;
				ground = false;
			}
		}
		return best <= exitT;
	});
	if (!ground && bestPrim < 0) return false;
	hit.t = best;
	hit.p = o + d * best;
	const float lod = footprint * best;
	if (ground)
	{
		hit.prim = -1;
		hit.p.z = 0;
		groundSurface(hit.p, lod, hit);
	}
	else
	{
		hit.prim = bestPrim;
		hit.n = bestN;
		surfaceOf(m_prims[static_cast<size_t>(bestPrim)], lod, wind, hit);
	}
	return true;
}

float Scene::sunTransmittance(const V3& p, const V3& n, const V3& sun, const V3& wind) const
{
	if (n.dot(sun) <= 0) return 0.0f;
	const V3 o = p + n * 0.01f;
	float T = 1.0f;
	Mailbox& mb = tlMailbox;
	mb.next(m_prims.size());
	const float sigma = 2.5f;  // leaf extinction (1/m): 1 m of dense leaves passes e^-2.5 = 8%
	const float kInterior = 0.03f;  // mean leaf cover inside the shell (branches, sparse leaves)
	const float step = 0.6f * static_cast<float>(m_opts.leaf_scale_m);
	walk(o, sun, 1e4f, [&](uint32_t first, uint32_t last, float) {
		for (uint32_t k = first; k < last; k++)
		{
			const uint32_t i = m_cellItems[k];
			if (mb.seen(i)) continue;
			const Primitive& pr = m_prims[i];
			float t;
			V3 nn;
			switch (pr.type)
			{
				case Primitive::Box:
					if (hitBox(pr, o, sun, kEps, 1e4f, t, nn)) T = 0;
					break;
				case Primitive::Cylinder:
					if (hitCylinder(pr, o, sun, kEps, 1e4f, t, nn)) T = 0;
					break;
				case Primitive::Ellipsoid:
				{
					float t0, t1;
					if (!ellipsoidChord(pr, o, sun, t0, t1) || t1 <= kEps) break;
					if (!pr.canopy)
					{
						if (t0 > kEps) T = 0;
						break;
					}
					// Optical depth through the leaf field along the chord.
					// Leaves sit in the outer shell of the crown (normalised
					// radius > 0.8); the sparse interior gets a constant density.
					t0 = std::max(t0, 0.0f);
					const int ns = std::clamp(static_cast<int>((t1 - t0) / step) + 1, 2, 12);
					const float dt = (t1 - t0) / ns;
					float tau = 0;
					for (int j = 0; j < ns; j++)
					{
						const V3 q = o + sun * (t0 + (j + 0.5f) * dt);
						const float ux = (q.x - pr.c.x) / pr.h.x, uy = (q.y - pr.c.y) / pr.h.y,
									uz = (q.z - pr.c.z) / pr.h.z;
						tau += (ux * ux + uy * uy + uz * uz) > 0.64f ? leafCover(pr, q, wind) : kInterior;
					}
					T *= std::exp(-sigma * tau * dt);
					if (T < 0.005f) T = 0;
					break;
				}
			}
			if (T == 0) return true;
		}
		return false;
	});
	return T;
}

}  // namespace shadyloc::sim
