/* ShadyLoc — offscreen trajectory snapshots. */
#include <shadyloc/render/SceneSnapshot.h>
#include <shadyloc/render/TrajectorySnapshot.h>

#include <mrpt/img/CImage.h>
#include <mrpt/opengl/COpenGLScene.h>
#include <mrpt/opengl/CSetOfTriangles.h>
#include <mrpt/poses/CPose3D.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace shadyloc::render
{
namespace
{
// Maps a point to picture coordinates (x right, y up the page, z out of it).
struct Projection
{
	int u = 0, v = 1, w = 2;  // indices of the world axes that become x, y, z
	double su = 1, sv = 1, sw = 1;	// and their signs (keeping a right-handed view)
	mrpt::math::TPoint3D operator()(const mrpt::math::TPoint3D& p) const
	{
		const double c[3] = {p.x, p.y, p.z};
		return {su * c[u], sv * c[v], sw * c[w]};
	}
};

Projection chooseProjection(const std::vector<std::vector<mrpt::math::TPoint3D>>& sets, char up)
{
	if (up == 'a')
	{
		double lo[3], hi[3];
		std::fill(lo, lo + 3, std::numeric_limits<double>::max());
		std::fill(hi, hi + 3, std::numeric_limits<double>::lowest());
		for (const auto& l : sets)
			for (const auto& p : l)
			{
				const double c[3] = {p.x, p.y, p.z};
				for (int i = 0; i < 3; i++) lo[i] = std::min(lo[i], c[i]), hi[i] = std::max(hi[i], c[i]);
			}
		int best = 2;
		for (int i = 0; i < 3; i++)
			if (hi[i] - lo[i] < hi[best] - lo[best]) best = i;
		up = "xyz"[best];
	}
	// Right-handed (page x right, page y up, z towards the viewer).
	switch (up)
	{
		case 'x': return {1, 2, 0};
		// Camera frames (z forward, x right, y down): forward is right on the
		// page, the camera's right is down the page, -y towards the viewer.
		case 'y': return {2, 0, 1, 1, -1, -1};
		case 'z': return {0, 1, 2};
	}
	throw std::invalid_argument(std::string("upAxis must be x, y, z or a, got '") + up + "'");
}

/** The projection as a rotation (each projection is a proper one): world
 * objects under a frame with this pose appear as the projected points do. */
mrpt::poses::CPose3D asPose(const Projection& p)
{
	mrpt::math::CMatrixDouble44 M = mrpt::math::CMatrixDouble44::Identity();
	const int idx[3] = {p.u, p.v, p.w};
	const double sg[3] = {p.su, p.sv, p.sw};
	for (int r = 0; r < 3; r++)
		for (int c = 0; c < 3; c++) M(r, c) = c == idx[r] ? sg[r] : 0.0;
	return mrpt::poses::CPose3D(M);
}
/** Where the picture's content goes: metres per pixel, the point the camera
 * looks at, and the legend band's text rows (fractions of the height). */
struct TFraming
{
	double mPerPx = 0, cx = 0, cy = 0, lineH = 0, top = 0;
};

TFraming frameContent(
	const std::vector<std::vector<mrpt::math::TPoint3D>>& sets, const Projection& proj, size_t legendLines,
	const SnapshotOptions& o)
{
	double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
	for (const auto& s : sets)
		for (const auto& p : s)
		{
			const auto q = proj(p);
			x0 = std::min(x0, q.x), x1 = std::max(x1, q.x), y0 = std::min(y0, q.y), y1 = std::max(y1, q.y);
		}
	TFraming f;
	// Text sizes are in pixels: the lines' spacing too (as fractions of the
	// height). The legend's lines (21 px each, below the title's) take a band
	// at the top; the content is framed in the rest.
	f.lineH = 21.0 / o.height, f.top = 1.0 - 24.0 / o.height;
	const double band = o.legendBand && legendLines ? f.lineH * double(legendLines) + 30.0 / o.height : 0.0;
	const double usableH = o.height * (1.0 - band) - 2 * o.marginFraction * o.height;
	// Metres per pixel so that the extent fits with the margin.
	f.mPerPx = std::max(
		{(x1 - x0) / (o.width * (1.0 - 2 * o.marginFraction)), (y1 - y0) / std::max(1.0, usableH), 1e-3 / o.width});
	// The camera looks at the picture's centre: that is half a band above the content's centre.
	f.cx = 0.5 * (x0 + x1), f.cy = 0.5 * (y0 + y1) + 0.5 * band * o.height * f.mPerPx;
	return f;
}

/** The object layers turned into the picture's frame; widens [zLow, zTop]
 * to hold them (the grid goes under them, the paths over them). */
std::vector<mrpt::opengl::CSetOfObjects::Ptr> objectFrames(
	const std::vector<TObjectLayer>& objects, const Projection& proj, double mPerPx, double& zLow, double& zTop)
{
	std::vector<mrpt::opengl::CSetOfObjects::Ptr> frames;
	for (const auto& l : objects)
	{
		if (!l.make) continue;
		auto obj = l.make(mPerPx);
		if (!obj) continue;
		auto frame = mrpt::opengl::CSetOfObjects::Create();
		frame->setPose(asPose(proj));
		frame->insert(obj);
		frames.push_back(frame);
		const auto bb = frame->getBoundingBox();
		if (bb.min.z <= bb.max.z && std::isfinite(bb.min.z) && std::isfinite(bb.max.z))
		{
			zLow = std::min(zLow, bb.min.z - 1.0);
			zTop = std::max(zTop, bb.max.z + 0.01);
		}
	}
	return frames;
}

/** Two triangles of one colour over the quad a, b, c, d. */
void insertQuad(
	mrpt::opengl::CSetOfTriangles& tris, const mrpt::math::TPoint3Df& a, const mrpt::math::TPoint3Df& b,
	const mrpt::math::TPoint3Df& c, const mrpt::math::TPoint3Df& d, const mrpt::img::TColor& colour)
{
	mrpt::opengl::TTriangle t1(a, b, c), t2(a, c, d);
	for (auto* t : {&t1, &t2})
		for (auto& v : t->vertices) v.setColor(colour);
	tris.insertTriangle(t1);
	tris.insertTriangle(t2);
}

/** A grid of a round number of metres, about 10 lines across, at height z,
 * with its step written in the corner. */
void insertGrid(mrpt::opengl::COpenGLScene& scene, const TFraming& f, const SnapshotOptions& o, double z)
{
	const double raw = f.mPerPx * o.width / 10;
	const double p10 = std::pow(10.0, std::floor(std::log10(raw)));
	const double step = raw / p10 < 2 ? p10 : (raw / p10 < 5 ? 2 * p10 : 5 * p10);
	const double hw = 0.5 * f.mPerPx * o.width, hh = 0.5 * f.mPerPx * o.height;
	// Lines as 1 px wide quads, inserted first: the offscreen renderer draws
	// line primitives over triangles whatever their depth.
	auto grid = mrpt::opengl::CSetOfTriangles::Create();
	const double gx0 = std::floor((f.cx - hw) / step) * step, gx1 = std::ceil((f.cx + hw) / step) * step,
				 gy0 = std::floor((f.cy - hh) / step) * step, gy1 = std::ceil((f.cy + hh) / step) * step;
	const double lw = 0.5 * f.mPerPx;
	const mrpt::img::TColor grey(210, 210, 210);
	auto quad = [&](double ax, double ay, double bx, double by) {
		insertQuad(*grid, {float(ax), float(ay), float(z)}, {float(bx), float(ay), float(z)},
			{float(bx), float(by), float(z)}, {float(ax), float(by), float(z)}, grey);
	};
	for (double x = gx0; x <= gx1 + 1e-9 * step; x += step) quad(x - lw, gy0, x + lw, gy1);
	for (double y = gy0; y <= gy1 + 1e-9 * step; y += step) quad(gx0, y - lw, gx1, y + lw);
	grid->enableLight(false);
	scene.insert(grid);
	mrpt::opengl::TFontParams font;
	font.color = {0.3f, 0.3f, 0.3f};
	font.vfont_scale = 14;
	scene.getViewport()->addTextMessage(0.01, 0.01, mrpt::format("grid %g m", step), 1, font);
}

/** A path as quads of its width (each segment extended by half a width, so
 * consecutive quads overlap at the joints), with its markers, at height z. */
mrpt::opengl::CSetOfTriangles::Ptr pathTriangles(
	const TrajectoryLayer& l, const Projection& proj, double mPerPx, float z)
{
	auto tris = mrpt::opengl::CSetOfTriangles::Create();
	const double hw = 0.5 * l.widthPx * mPerPx;
	for (size_t i = 0; i + 1 < l.points.size(); i++)
	{
		const auto a = proj(l.points[i]), b = proj(l.points[i + 1]);
		double dx = b.x - a.x, dy = b.y - a.y;
		const double len = std::hypot(dx, dy);
		if (len < 1e-12) continue;
		dx /= len, dy /= len;
		const double ex = dx * hw, ey = dy * hw, nx = -dy * hw, ny = dx * hw;
		const auto c = i < l.segmentColours.size() ? l.segmentColours[i] : l.colour;
		insertQuad(*tris, {float(a.x - ex + nx), float(a.y - ey + ny), z}, {float(a.x - ex - nx), float(a.y - ey - ny), z},
			{float(b.x + ex - nx), float(b.y + ey - ny), z}, {float(b.x + ex + nx), float(b.y + ey + ny), z}, c);
	}
	if (l.markerPx > 0)
	{
		const double h = 0.5 * l.markerPx * mPerPx;
		const float zm = z + 0.005f;
		for (const auto& pt : l.points)
		{
			const auto q = proj(pt);
			insertQuad(*tris, {float(q.x - h), float(q.y - h), zm}, {float(q.x + h), float(q.y - h), zm},
				{float(q.x + h), float(q.y + h), zm}, {float(q.x - h), float(q.y + h), zm}, l.markerColour);
		}
	}
	tris->enableLight(false);
	return tris;
}

/** One legend line, "-- text" in its colour, the li-th below the title. */
void legendLine(mrpt::opengl::COpenGLViewport& vp, const TFraming& f, size_t li, const std::string& text, const mrpt::img::TColor& colour)
{
	mrpt::opengl::TFontParams font;
	font.color = mrpt::img::TColorf(colour);
	font.vfont_scale = 16;
	vp.addTextMessage(0.01, f.top - f.lineH * double(li + 1), "-- " + text, 10 + li, font);
}

/** The legend: each drawn layer's lines, then the object layers'. */
void drawLegend(
	mrpt::opengl::COpenGLViewport& vp, const TFraming& f, const std::vector<TrajectoryLayer>& layers,
	const std::vector<TObjectLayer>& objects)
{
	size_t li = 0;
	for (const auto& l : layers)
	{
		if (l.points.size() < 2) continue;
		if (l.legend.empty()) legendLine(vp, f, li++, l.name, l.colour);
		for (const auto& [text, colour] : l.legend) legendLine(vp, f, li++, text, colour);
	}
	for (const auto& l : objects)
		for (const auto& [text, colour] : l.legend) legendLine(vp, f, li++, text, colour);
}
}  // namespace

mrpt::img::CImage renderTrajectoriesImage(
	const std::vector<TrajectoryLayer>& layers, const SnapshotOptions& o, const std::vector<TObjectLayer>& objects,
	const std::string& what)
{
	std::vector<std::vector<mrpt::math::TPoint3D>> sets;
	for (const auto& l : layers) sets.push_back(l.points);
	for (const auto& l : objects) sets.push_back(l.extent);
	size_t n = 0;
	for (const auto& s : sets) n += s.size();
	if (n < 2) throw std::runtime_error(what + ": nothing to draw (fewer than two points)");
	const Projection proj = chooseProjection(sets, o.upAxis);
	size_t lines = o.title.empty() ? 0 : 1;
	for (const auto& l : layers) lines += l.points.size() < 2 || !o.legend ? 0 : (l.legend.empty() ? 1 : l.legend.size());
	for (const auto& l : objects) lines += o.legend ? l.legend.size() : 0;
	const TFraming f = frameContent(sets, proj, lines, o);

	mrpt::opengl::COpenGLScene scene;
	auto vp = scene.getViewport();
	vp->setCustomBackgroundColor({1.0f, 1.0f, 1.0f});
	double zLow = -1.0, zTop = 0.0;
	const auto frames = objectFrames(objects, proj, f.mPerPx, zLow, zTop);
	if (o.grid) insertGrid(scene, f, o, zLow);
	for (const auto& fr : frames) scene.insert(fr);

	size_t li = 0;
	for (const auto& l : layers)
	{
		if (l.points.size() < 2) continue;
		// Over the objects; later layers on top.
		scene.insert(pathTriangles(l, proj, f.mPerPx, float(zTop + 0.01 * double(li++))));
	}
	if (o.legend) drawLegend(*vp, f, layers, objects);
	if (!o.title.empty())
	{
		mrpt::opengl::TFontParams font;
		font.color = {0.f, 0.f, 0.f};
		font.vfont_scale = 18;
		vp->addTextMessage(0.01, f.top, o.title, 2, font);
	}

	TSceneCamera cam;
	cam.auto_frame = false;
	cam.orthographic = true;
	cam.pointing_at = {f.cx, f.cy, 0.0};
	cam.azimuth_deg = -90;
	cam.elevation_deg = 90;
	// In orthographic mode MRPT 2.5 shows a vertical extent of half the zoom
	// distance (measured: a 48 m tall view at zoom 95 m).
	cam.zoom_distance = 2.0 * f.mPerPx * o.height;
	return snapshotScene(scene, o.width, o.height, cam);
}

void renderTrajectories(
	const std::vector<TrajectoryLayer>& layers, const SnapshotOptions& o, const std::string& pngPath,
	const std::vector<TObjectLayer>& objects)
{
	writePngAtomically(renderTrajectoriesImage(layers, o, objects, "'" + pngPath + "'"), pngPath);
}

}  // namespace shadyloc::render
