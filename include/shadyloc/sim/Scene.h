/* ShadyLoc simulator — the world: a route, its ground, and the primitives
 * standing along it (boxes, vertical cylinders, ellipsoids), with a 2D grid
 * for ray casting and procedural textures.
 *
 * World frame: x east, y north, z up (m); the ground is the plane z = 0. The
 * route runs roughly along +x as y = A sin(2 pi x / L + phi). Route coordinates
 * (s, d): arc length s along the route (m) and lateral offset d, + = left of
 * the direction of travel (m).
 */
#pragma once

#include <shadyloc/sim/SimOptions.h>
#include <shadyloc/sim/Spectral.h>

#include <cmath>
#include <cstdint>
#include <vector>

namespace shadyloc::sim
{
/** Minimal float 3-vector for the ray caster's inner loops. */
struct V3
{
	float x = 0, y = 0, z = 0;
	V3() = default;
	V3(float a, float b, float c) : x(a), y(b), z(c) {}
	V3 operator+(const V3& o) const { return {x + o.x, y + o.y, z + o.z}; }
	V3 operator-(const V3& o) const { return {x - o.x, y - o.y, z - o.z}; }
	V3 operator*(float s) const { return {x * s, y * s, z * s}; }
	V3 operator-() const { return {-x, -y, -z}; }
	float dot(const V3& o) const { return x * o.x + y * o.y + z * o.z; }
	float norm() const { return std::sqrt(dot(*this)); }
	V3 normalized() const { return *this * (1.0f / norm()); }
};

/** Surface materials. Each has two basis reflectance spectra; textures mix
 * them per point (chromatic variation) and scale the result (brightness). */
enum Material : uint8_t
{
	kSky = 0,
	kAsphalt,
	kPaint,	 //!< road markings
	kPaving,  //!< sidewalk slabs
	kGrass,
	kBrick,	 //!< basis B is the mortar
	kRender,  //!< painted facade plaster
	kConcrete,
	kGlass,	 //!< windows (dark)
	kBark,
	kFoliage,
	kMarker,  //!< purple test spheres
	kMaterialCount
};
const char* materialName(int m);
/** Basis reflectance j (0 = A, 1 = B) of material m. */
ReflectanceModel materialReflectance(int m, int j);

/** The route's centre line and its (s, d) coordinates. */
class Route
{
   public:
	Route() = default;
	Route(double length_m, double amplitude_m, double phase_rad);

	double length() const { return m_length; }
	/** Centre line y at x, its slope dy/dx. */
	double centreY(double x) const { return m_A * std::sin(m_k * x + m_phase); }
	double slope(double x) const { return m_A * m_k * std::cos(m_k * x + m_phase); }
	/** World x of the centre-line point at arc length s (table, linear). */
	double xAt(double s) const;
	/** Arc length at world x. */
	double sAt(double x) const;
	/** World point (x, y) and heading (rad from +x, CCW) at (s, d). */
	void pointAt(double s, double d, double& x, double& y, double& heading) const;
	/** (s, d) of a world point near the route (first order in curvature). */
	void coords(float x, float y, float& s, float& d) const;

   private:
	double m_length = 0, m_A = 0, m_k = 0, m_phase = 0;
	double m_x0 = 0, m_dx = 0.25;  //!< arc table: x samples from m_x0 every m_dx
	std::vector<double> m_s;  //!< arc length at each x sample (s = 0 at x = 0)
};

/** One solid: box (yawed about z), vertical cylinder, or axis-aligned
 * ellipsoid. A canopy ellipsoid is leafy: light passes through its gaps. */
struct Primitive
{
	enum Type : uint8_t
	{
		Box,
		Cylinder,
		Ellipsoid
	};
	Type type = Box;
	uint8_t material = kConcrete;
	bool canopy = false;  //!< leafy ellipsoid (procedural gaps)
	bool windows = false;  //!< box facades carry a window grid
	V3 c;  //!< box/ellipsoid centre; cylinder base centre (m)
	V3 h;  //!< box half sizes (local x,y,z); ellipsoid radii; cylinder (r, r, height) (m)
	float cosYaw = 1, sinYaw = 0;  //!< box orientation
	uint32_t seed = 0;	//!< texture/leaf seed
	float bx0 = 0, by0 = 0, bx1 = 0, by1 = 0, zTop = 0;	 //!< xy bounds, top (m)
};

/** What a camera ray sees: the point, its normal, material and texture. */
struct SurfaceHit
{
	float t = 0;  //!< ray parameter (m, rays have unit direction)
	V3 p, n;  //!< point, unit normal facing the ray's origin side
	uint8_t material = kSky;
	float mix = 0;	//!< weight of basis spectrum B, [0,1]
	float brightness = 1;  //!< texture scale on the reflectance
	int prim = -1;	//!< primitive index, -1 = ground or sky
};

class Scene
{
   public:
	/** Lays out the world from the options (deterministic in opts.seed). */
	explicit Scene(const TSimSceneOptions& opts);

	const TSimSceneOptions& options() const { return m_opts; }
	const Route& route() const { return m_route; }
	const std::vector<Primitive>& primitives() const { return m_prims; }

	/** Adds a primitive after construction; call build() before casting. */
	void add(const Primitive& p);
	/** Rebuilds the grid (the constructor already did). */
	void build();

	/** Nearest surface along o + t d (|d| = 1), t in (0, tmax]. footprint:
	 * pixel footprint per metre of range (rad), for texture level of detail.
	 * windOffset: leaf-pattern shift. False = sky. */
	bool intersect(const V3& o, const V3& d, float tmax, float footprint, const V3& windOffset,
		SurfaceHit& hit) const;

	/** Fraction of direct sunlight reaching p (normal n) along unit sunDir:
	 * 0 behind a solid, leaf transmittance through canopies, 1 in the open. */
	float sunTransmittance(const V3& p, const V3& n, const V3& sunDir, const V3& windOffset) const;

	/** Leaf density field of a canopy in [0,1] (1 = leaf). */
	float leafCover(const Primitive& pr, const V3& p, const V3& windOffset) const;

	/** Per-tree wind offset: the traversal's wind seed shifts every canopy's
	 * leaf pattern by up to canopy_wind_m. */
	V3 windOffset(uint32_t windSeed) const;

	/** Texture of the ground material at p (world, z = 0). */
	void groundSurface(const V3& p, float lod, SurfaceHit& hit) const;

   private:
	void layout();
	void surfaceOf(const Primitive& pr, float lod, const V3& wind, SurfaceHit& hit) const;

	/** Calls visit(first, last, tExit) for the primitive index range of each
	 * grid cell the ray crosses in order, until it returns true. */
	template <class Visit>
	void walk(const V3& o, const V3& d, float tmax, Visit&& visit) const;

	TSimSceneOptions m_opts;
	Route m_route;
	std::vector<Primitive> m_prims;
	float m_leafThreshold = 0;	//!< leaf noise above this = leaf

	// Grid over xy: cells of m_cell metres, CSR lists of primitive indices.
	float m_gx0 = 0, m_gy0 = 0, m_cell = 4.0f, m_zTop = 0;
	int m_nx = 0, m_ny = 0;
	std::vector<uint32_t> m_cellStart, m_cellItems;
};

}  // namespace shadyloc::sim
