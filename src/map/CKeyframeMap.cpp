/* ShadyLoc — the dual-channel keyframe map. */
#include "ByteBuffer.h"

#include <shadyloc/core/Errors.h>
#include <shadyloc/core/Options.h>
#include <shadyloc/io/AtomicFile.h>
#include <shadyloc/map/CKeyframeMap.h>

#include <shadyloc/geometry/PoseCovariance.h>

#include <mrpt/config/CConfigFileBase.h>
#include <mrpt/io/CMemoryStream.h>
#include <mrpt/opengl/CPointCloudColoured.h>
#include <mrpt/opengl/CSetOfObjects.h>
#include <mrpt/opengl/CSetOfTriangles.h>
#include <mrpt/poses/CPose3D.h>
#include <mrpt/serialization/CArchive.h>

#include <Eigen/Eigenvalues>

#include <zstd.h>

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <memory>
#include <set>
#include <sstream>

using namespace shadyloc;
using shadyloc::map::detail::ByteReader;
using shadyloc::map::detail::ByteWriter;
namespace fs = std::filesystem;

IMPLEMENTS_SERIALIZABLE(CKeyframeMap, mrpt::maps::CMetricMap, shadyloc)
MAP_DEFINITION_REGISTER("shadyloc::CKeyframeMap,keyframeMap", shadyloc::CKeyframeMap)

namespace
{
// Registered when the library loads, after its class id (src/Registration.cpp).
[[maybe_unused]] const bool mapRegisteredAtLoad = (mrpt::rtti::registerClass(CLASS_ID(CKeyframeMap)), true);
}  // namespace

namespace
{
constexpr const char* kClass = "shadyloc::CKeyframeMap";
// Bytes per stored measurement: uL, v, disparity, response (u16 each), zncc
// (i8), BRIEF (32), patch.
constexpr size_t kMeasBytes = 2 + 2 + 2 + 2 + 1 + 32 + features::kPatchSize * features::kPatchSize;
constexpr size_t kNormalBytes = 3;	//!< version 4: the surface normal, 3 x int8
constexpr size_t kDisparitySigmaBytes = 1;	//!< version 6: a refined disparity's sigma
/** A refined disparity's sigma on disk: 1/128 px steps rounded up (never
 * more confident than computed), 1..255; 0 = none (the pair's own depth). */
constexpr double kDisparitySigmaStep = 1.0 / 128;
uint8_t disparitySigmaCode(double sigma)
{
	if (!(sigma > 0)) return 0;
	return static_cast<uint8_t>(std::clamp(std::ceil(sigma / kDisparitySigmaStep - 1e-9), 1.0, 255.0));
}
float disparitySigmaFromCode(uint8_t k) { return static_cast<float>(k * kDisparitySigmaStep); }
/** A refined disparity's sigma with the stored disparity's rounding to
 * 1/kPixelQuantum added (uniform: step^2 / 12); 0 stays 0 (the pair's model). */
double withStorageRounding(double sigma)
{
	const double q = 1.0 / CKeyframeMap::kPixelQuantum;
	return sigma > 0 ? std::sqrt(sigma * sigma + q * q / 12) : 0.0;
}

/** A unit normal as stored: each component times 127, rounded; (0, 0, 0) = unknown. */
std::array<int8_t, 3> normalCode(const Eigen::Vector3f& n)
{
	std::array<int8_t, 3> c{};
	for (int i = 0; i < 3; i++) c[i] = static_cast<int8_t>(std::clamp<long>(std::lround(n(i) * 127.f), -127, 127));
	return c;
}

/** The normal a stored code stands for, code / 127 (not renormalised, so
 * that coding it again gives the same code: a loaded map saves to the same
 * bytes); false for a code no unit normal makes (its length, 127 for a unit
 * normal, off by more than rounding can). */
bool normalFromCode(const std::array<int8_t, 3>& c, Eigen::Vector3f& n)
{
	n = Eigen::Vector3f(c[0], c[1], c[2]) / 127.f;
	const float len = n.norm();
	return len == 0.f || (len > 0.98f && len < 1.02f);
}
constexpr uint8_t kMaxChannels = 16;
/** Largest serialised map (and block) a reader accepts [bytes]: 64 GiB, far
 * beyond any map (150,000 keyframes of 120 measurements per channel are ~3.7 GB). */
constexpr uint64_t kMaxSerializedBytes = uint64_t(1) << 36;

/** A patch pixel kept to `bits` bits (its top bits q) as held in memory:
 * the middle of the range q stands for, so quantising again changes nothing. */
uint8_t dequantisePixel(uint8_t q, int bits)
{
	const int s = 8 - bits;
	return static_cast<uint8_t>((q << s) + (s > 0 ? 1 << (s - 1) : 0));
}

void putPose(ByteWriter& w, const Eigen::Isometry3d& T)
{
	for (int i = 0; i < 3; i++)
		for (int j = 0; j < 4; j++) w.put<double>(T.matrix()(i, j));
}
/** A pose as stored, unchecked (poseProblem says what is wrong with it). */
Eigen::Isometry3d readPose(ByteReader& r)
{
	Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
	for (int i = 0; i < 3; i++)
		for (int j = 0; j < 4; j++) T.matrix()(i, j) = r.get<double>();
	return T;
}
/** Why T is no rigid pose ("" when it is). */
std::string poseProblem(const Eigen::Isometry3d& T)
{
	if (!T.matrix().allFinite()) return "not finite";
	const Eigen::Matrix3d RtR = T.linear().transpose() * T.linear();
	if (!RtR.isApprox(Eigen::Matrix3d::Identity(), 1e-6)) return "rotation not orthonormal";
	return "";
}
Eigen::Isometry3d getPose(ByteReader& r, const char* what)
{
	const Eigen::Isometry3d T = readPose(r);
	if (const std::string why = poseProblem(T); !why.empty()) r.fail(std::string(what) + ": " + why);
	return T;
}
void putCov(ByteWriter& w, const geometry::Matrix6d& C)
{
	for (int i = 0; i < 6; i++)
		for (int j = i; j < 6; j++) w.put<double>(C(i, j));
}
/** A covariance as stored (its upper triangle), unchecked. */
geometry::Matrix6d readCov(ByteReader& r)
{
	geometry::Matrix6d C;
	for (int i = 0; i < 6; i++)
		for (int j = i; j < 6; j++) C(i, j) = C(j, i) = r.get<double>();
	return C;
}
geometry::Matrix6d getCov(ByteReader& r)
{
	const geometry::Matrix6d C = readCov(r);
	if (!C.allFinite()) r.fail("covariance not finite");
	return C;
}

/** Why a stored link cannot be used ("" when it can): it names a keyframe
 * the map lacks or one run twice, is not a pose with a covariance, or
 * contradicts the map poses it placed. appendExperience places each
 * keyframe a link reaches at exactly T_map_a T_a_b, so within one frame an
 * intact link agrees with the stored poses to rounding; the test allows its
 * covariance (chi^2, 6 dof, 99.9 %). */
std::string brokenLink(
	const map::TExperienceLink& l, const std::vector<map::TMapKeyframe>& kfs, const std::vector<uint16_t>& frameOfRun)
{
	if (l.a >= kfs.size() || l.b >= kfs.size()) return "the map has " + std::to_string(kfs.size()) + " keyframes";
	if (kfs[l.a].run == kfs[l.b].run) return "both keyframes of one run";
	if (std::string why = poseProblem(l.T_a_b); !why.empty()) return "pose " + why;
	if (!l.cov.allFinite()) return "covariance not finite";
	if (Eigen::SelfAdjointEigenSolver<geometry::Matrix6d>(l.cov).eigenvalues().minCoeff() < 0)
		return "covariance not positive semi-definite";
	if (frameOfRun[kfs[l.a].run] != frameOfRun[kfs[l.b].run]) return "";  // joins frames: nothing to compare with
	const Eigen::Isometry3d stored = kfs[l.a].T_map_kf.inverse() * kfs[l.b].T_map_kf;
	const double d2 = geometry::mahalanobis2(geometry::localLeft(stored, l.T_a_b), l.cov);
	constexpr double kChi2_6dof_999 = 22.46;
	if (d2 > kChi2_6dof_999 && (stored.translation() - l.T_a_b.translation()).norm() > 1e-6)
	{
		std::ostringstream m;
		m << "contradicts the map poses it placed (" << std::fixed << std::setprecision(3)
		  << (stored.translation() - l.T_a_b.translation()).norm() << " m apart, chi^2 " << std::setprecision(1) << d2
		  << ")";
		return m.str();
	}
	return "";
}

/** FNV-1a, 64 bit, of a block's position (version 3, channel blocks only)
 * and its stored (compressed) bytes: each step is a bijection of the state
 * for a given byte, so any single changed byte changes the sum. zstd's own
 * checksum covers the decompressed content only: a flipped bit the entropy
 * decoder ignores would pass it. The metadata names the channels in block
 * order, so with the position in the sum a channel block moved (two
 * channels' blocks swapped) fails too. Position 0 (the metadata, and every
 * block of versions 1-2) is plain FNV-1a of the bytes. */
uint64_t blockSum(const std::vector<uint8_t>& b, size_t position)
{
	uint64_t h = 0xcbf29ce484222325ull;
	if (position > 0) h = (h ^ static_cast<uint8_t>(position)) * 0x100000001b3ull;
	for (uint8_t x : b) h = (h ^ x) * 0x100000001b3ull;
	return h;
}

std::vector<uint8_t> compressBlock(const std::vector<uint8_t>& raw, int level)
{
	ZSTD_CCtx* c = ZSTD_createCCtx();
	if (!c) throw std::runtime_error(std::string(kClass) + ": zstd context");
	ZSTD_CCtx_setParameter(c, ZSTD_c_compressionLevel, level);
	ZSTD_CCtx_setParameter(c, ZSTD_c_checksumFlag, 1);	// any damaged byte fails the load
	ZSTD_CCtx_setParameter(c, ZSTD_c_contentSizeFlag, 1);
	std::vector<uint8_t> out(ZSTD_compressBound(raw.size()));
	const size_t n = ZSTD_compress2(c, out.data(), out.size(), raw.data(), raw.size());
	ZSTD_freeCCtx(c);
	if (ZSTD_isError(n)) throw std::runtime_error(std::string(kClass) + ": zstd: " + ZSTD_getErrorName(n));
	out.resize(n);
	return out;
}

/** Decompresses one block whose stored raw size is rawSize. Streams into a
 * buffer that grows with the output actually produced, so a frame header
 * claiming a huge size allocates nothing before its data proves it. */
std::vector<uint8_t> decompressBlock(const std::vector<uint8_t>& comp, uint64_t rawSize, const std::string& what)
{
	const unsigned long long fs = ZSTD_getFrameContentSize(comp.data(), comp.size());
	if (fs == ZSTD_CONTENTSIZE_ERROR || fs == ZSTD_CONTENTSIZE_UNKNOWN)
		throw io::CorruptDataError(what + ": not a zstd frame (damaged)");
	if (fs != rawSize)
		throw io::CorruptDataError(
			what + ": stored size " + std::to_string(rawSize) + " disagrees with the frame's " +
			std::to_string(fs) + " (damaged)");
	std::unique_ptr<ZSTD_DCtx, size_t (*)(ZSTD_DCtx*)> d(ZSTD_createDCtx(), ZSTD_freeDCtx);
	if (!d) throw std::runtime_error(what + ": zstd context");
	std::vector<uint8_t> raw;
	ZSTD_inBuffer in{comp.data(), comp.size(), 0};
	const size_t kStep = 1 << 20;
	for (;;)
	{
		const size_t at = raw.size();
		// At least one byte of room: output beyond rawSize shows a lying size.
		const size_t room = std::max<size_t>(std::min<uint64_t>(kStep, rawSize - at), 1);
		raw.resize(at + room);
		ZSTD_outBuffer out{raw.data() + at, room, 0};
		const size_t inBefore = in.pos;
		const size_t ret = ZSTD_decompressStream(d.get(), &out, &in);
		if (ZSTD_isError(ret)) throw io::CorruptDataError(what + ": " + ZSTD_getErrorName(ret) + " (damaged)");
		raw.resize(at + out.pos);
		if (raw.size() > rawSize) throw io::CorruptDataError(what + ": more data than its stored size (damaged)");
		if (ret == 0) break;  // the frame is complete
		if (out.pos == 0 && in.pos == inBefore)
			throw io::CorruptDataError(what + ": the zstd frame ends early (damaged)");
	}
	if (raw.size() != rawSize || in.pos != in.size)
		throw io::CorruptDataError(what + ": short or trailing data in the block (damaged)");
	return raw;
}

/** Reads n stored bytes in chunks through the bounded reader, so a damaged
 * size can neither pass the budget nor allocate more than the stream holds. */
std::vector<uint8_t> readBlob(io::BoundedReader& r, uint64_t n, const char* field)
{
	if (n > r.remaining())
		r.fail(field, "needs " + std::to_string(n) + " bytes, only " + std::to_string(r.remaining()) +
						  " can remain (truncated or corrupt)");
	std::vector<uint8_t> out;
	const size_t kChunk = 1 << 20;
	while (out.size() < n)
	{
		const size_t k = std::min<uint64_t>(kChunk, n - out.size());
		const size_t at = out.size();
		out.resize(at + k);
		r.readBytes(out.data() + at, k, field);
	}
	return out;
}

void putChannel(ByteWriter& w, const map::TChannelParams& c)
{
	w.str(c.label);
	w.str(c.filter_class);
	w.str(c.filter_options);
	w.put<int32_t>(c.brief_patch_size);
	w.put<uint32_t>(c.brief_seed);
	w.put<double>(c.presmooth_sigma);
	w.put<double>(c.sigma_px);
	// version 4
	w.put<uint8_t>(static_cast<uint8_t>(c.descriptor));
	w.put<int32_t>(c.orb_levels);
	w.put<double>(c.orb_scale_factor);
}
/** A channel as stored by format `version`: before version 4 every map was
 * FAST + BRIEF (the ORB fields keep their defaults). */
map::TChannelParams getChannel(ByteReader& r, uint8_t version)
{
	map::TChannelParams c;
	c.label = r.str();
	c.filter_class = r.str();
	c.filter_options = r.str();
	c.brief_patch_size = r.get<int32_t>();
	c.brief_seed = r.get<uint32_t>();
	c.presmooth_sigma = r.get<double>();
	c.sigma_px = r.get<double>();
	if (version >= 4)
	{
		const auto kind = r.get<uint8_t>();
		if (kind > 1) r.fail("channel '" + c.label + "': descriptor kind " + std::to_string(kind) + " unknown");
		c.descriptor = static_cast<features::DescriptorKind>(kind);
		c.orb_levels = r.get<int32_t>();
		c.orb_scale_factor = r.get<double>();
		if (c.orb_levels < 1) r.fail("channel '" + c.label + "': ORB levels");
		if (!(c.orb_scale_factor > 1) || !std::isfinite(c.orb_scale_factor)) r.fail("channel '" + c.label + "': ORB scale factor");
	}
	if (c.label.empty()) r.fail("channel without a label");
	if (c.filter_class.empty()) r.fail("channel '" + c.label + "': no filter class");
	if (c.brief_patch_size <= 0) r.fail("channel '" + c.label + "': BRIEF patch size");
	if (!(c.presmooth_sigma >= 0) || !std::isfinite(c.presmooth_sigma)) r.fail("channel '" + c.label + "': presmooth_sigma");
	if (!(c.sigma_px > 0) || !std::isfinite(c.sigma_px)) r.fail("channel '" + c.label + "': sigma_px");
	return c;
}

void putOptions(ByteWriter& w, const TKeyframeMapOptions& o)
{
	w.put<double>(o.kf_spacing_m);
	w.put<double>(o.kf_spacing_deg);
	w.put<int32_t>(o.landmarks_per_keyframe);
	w.put<int32_t>(o.selection_grid_cols);
	w.put<int32_t>(o.selection_grid_rows);
	w.put<int32_t>(o.compression_level);
	w.put<double>(o.index_cell_m);
	w.put<uint8_t>(o.draw_landmarks);
	w.put<double>(o.draw_landmark_max_depth_m);
	w.put<double>(o.draw_frame_every_m);
	// version 2
	w.put<uint8_t>(static_cast<uint8_t>(o.landmark_selection));
	w.put<double>(o.reobservation_window_m);
	w.put<double>(o.reobservation_radius_px);
	w.put<int32_t>(o.min_reobservations);
	w.put<int32_t>(o.patch_bits);
	// version 6
	w.put<uint8_t>(o.depth_from_reobservations);
	w.put<double>(o.reobservation_sigma_px);
}
/** The options as stored by format `version`: version 1 maps were thinned
 * by the strongest corners (the only selection then). */
TKeyframeMapOptions getOptions(ByteReader& r, uint8_t version)
{
	TKeyframeMapOptions o;
	o.kf_spacing_m = r.get<double>();
	o.kf_spacing_deg = r.get<double>();
	o.landmarks_per_keyframe = r.get<int32_t>();
	o.selection_grid_cols = r.get<int32_t>();
	o.selection_grid_rows = r.get<int32_t>();
	o.compression_level = r.get<int32_t>();
	o.index_cell_m = r.get<double>();
	const auto d = r.get<uint8_t>();
	if (d > 1) r.fail("draw_landmarks is not a bool");
	o.draw_landmarks = d;
	o.draw_landmark_max_depth_m = r.get<double>();
	o.draw_frame_every_m = r.get<double>();
	if (version >= 2)
	{
		const auto sel = r.get<uint8_t>();
		if (sel > 1) r.fail("landmark_selection " + std::to_string(sel) + " unknown");
		o.landmark_selection = static_cast<TKeyframeMapOptions::LandmarkSelection>(sel);
		o.reobservation_window_m = r.get<double>();
		o.reobservation_radius_px = r.get<double>();
		o.min_reobservations = r.get<int32_t>();
		o.patch_bits = r.get<int32_t>();
	}
	else
	{
		o.landmark_selection = TKeyframeMapOptions::LandmarkSelection::Strongest;
		o.patch_bits = 8;
	}
	o.depth_from_reobservations = false;  // before version 6 every depth was the pair's
	if (version >= 6)
	{
		const auto d = r.get<uint8_t>();
		if (d > 1) r.fail("depth_from_reobservations is not a bool");
		o.depth_from_reobservations = d;
		o.reobservation_sigma_px = r.get<double>();
	}
	try
	{
		o.validate();
	}
	catch (const std::exception& e)
	{
		r.fail(std::string("stored options: ") + e.what());
	}
	return o;
}
}  // namespace

// ============================================================================
// Options
// ============================================================================
void TKeyframeMapOptions::keys(core::KeyVisitor& v)
{
	using core::Range;
	v("kf_spacing_m", kf_spacing_m, "m", Range::atLeast(0), "a new map keyframe after this path distance along the VO chain");
	v("kf_spacing_deg", kf_spacing_deg, "deg", Range::openClosed(0, 180), "... or this change of heading");
	v("landmarks_per_keyframe", landmarks_per_keyframe, "", Range::atLeast(0),
	  "kept per keyframe and channel, the best (landmark_selection) per image bucket first; 0 = all");
	v.choice("landmark_selection", landmark_selection,
			 {{"strongest", LandmarkSelection::Strongest}, {"reobserved", LandmarkSelection::Reobserved}},
			 "strongest (FAST response) | reobserved (re-found most often by the survey's own frames)");
	v("reobservation_window_m", reobservation_window_m, "m", Range::above(0),
	  "reobserved: survey frames within this path distance of the keyframe are matched");
	v("reobservation_radius_px", reobservation_radius_px, "px", Range::closed(1, 200),
	  "reobserved: search circle around a landmark's projection at the VO pose");
	v("min_reobservations", min_reobservations, "", Range::atLeast(0),
	  "reobserved: landmarks re-found in fewer frames are dropped (0 = as the budget allows)");
	v("depth_from_reobservations", depth_from_reobservations, "", Range::any(),
	  "each kept landmark's depth refined by the survey frames that re-found it (matters seen from aside)");
	v("reobservation_sigma_px", reobservation_sigma_px, "px", Range::above(0),
	  "depth_from_reobservations: a re-observation's pixel noise (calibrated against true depth)");
	v("selection_grid_cols", selection_grid_cols, "", Range::closed(1, 256), "landmark selection buckets across the image");
	v("selection_grid_rows", selection_grid_rows, "", Range::closed(1, 256), "... and down the image");
	v("patch_bits", patch_bits, "", Range::closed(1, 8), "bits kept of each stored patch pixel, 1..8 (fewer compress better)");
	v("surface_normals", surface_normals, "", Range::any(),
	  "store a surface normal per landmark (patches warped to the live viewpoint)");
	v("normal_window_px", normal_window_px, "px", Range::closed(2, 32),
	  "normals: plane fitted to the (2r+1)^2 dense disparities around a landmark");
	v("compression_level", compression_level, "", Range::closed(1, 22), "zstd level 1 (fast) .. 22 (small)");
	v("index_cell_m", index_cell_m, "m", Range::above(0), "cell of the spatial hash grid over camera centres");
	v("draw_landmarks", draw_landmarks, "", Range::any(), "drawings show landmarks, coloured by channel");
	v("draw_landmark_max_depth_m", draw_landmark_max_depth_m, "m", Range::above(0), "farther landmarks are not drawn");
	v("draw_frame_every_m", draw_frame_every_m, "m", Range::atLeast(0),
	  "a keyframe marker (chevron) at most this often along the path");
}

void TKeyframeMapOptions::loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s)
{
	core::loadKeys(*this, c, s);
}

void TKeyframeMapOptions::dumpToTextStream(std::ostream& out) const { core::dumpKeys(*this, out); }

void TKeyframeMapOptions::validate() const { core::checkKeys(*this); }

std::string shadyloc::toString(TKeyframeMapOptions::LandmarkSelection s)
{
	return s == TKeyframeMapOptions::LandmarkSelection::Strongest ? "strongest" : "reobserved";
}

bool TKeyframeMapOptions::operator==(const TKeyframeMapOptions& o) const
{
	ByteWriter a, b;
	putOptions(a, *this);
	putOptions(b, o);
	return a.buf == b.buf;
}

// ============================================================================
// Building
// ============================================================================
void CKeyframeMap::setup(
	const geometry::TStereoCalib& calib, int w, int h, const std::vector<map::TChannelParams>& channels)
{
	if (!m_keyframes.empty())
		throw std::logic_error(std::string(kClass) + "::setup: the map already holds keyframes");
	if (channels.empty() || channels.size() > kMaxChannels)
		throw std::invalid_argument(std::string(kClass) + "::setup: 1.." + std::to_string(kMaxChannels) + " channels");
	for (size_t i = 0; i < channels.size(); i++)
		for (size_t j = 0; j < i; j++)
			if (channels[i].label == channels[j].label)
				throw std::invalid_argument(std::string(kClass) + "::setup: channel '" + channels[i].label + "' twice");
	if (w <= 0 || h <= 0 || w * kPixelQuantum > 65535 || h * kPixelQuantum > 65535)
		throw std::invalid_argument(
			std::string(kClass) + "::setup: image size " + std::to_string(w) + "x" + std::to_string(h) +
			" cannot be stored (at most " + std::to_string(65535 / kPixelQuantum) + " px a side)");
	m_calib = calib;
	m_width = w;
	m_height = h;
	m_channels = channels;
}

void CKeyframeMap::checkCompatible(const map::TChannelParams& live) const
{
	const size_t i = channelIndex(live.label);
	const std::string d = m_channels[i].differences(live);
	if (!d.empty())
		throw std::runtime_error(
			std::string(kClass) + ": live channel '" + live.label + "' was made with other descriptor parameters (" + d +
			"): map " + m_channels[i].asString() + "; live " + live.asString());
}

uint16_t CKeyframeMap::addRun(const std::string& name, int frame)
{
	for (size_t i = 0; i < m_runs.size(); i++)
		if (m_runs[i] == name) return static_cast<uint16_t>(i);
	if (m_runs.size() >= 65535) throw std::length_error(std::string(kClass) + ": too many runs");
	const auto index = static_cast<uint16_t>(m_runs.size());
	// The first run defines the map frame; another shares the frame of one that founded it.
	if (m_runs.empty() ? frame > 0 : (frame >= int(m_runs.size()) || (frame > 0 && m_runFrame[frame] != frame)))
		throw std::invalid_argument(
			std::string(kClass) + "::addRun: run '" + name + "' cannot be in the frame of run " + std::to_string(frame));
	m_runs.push_back(name);
	m_runFrame.push_back(frame == kOwnFrame && index > 0 ? index : static_cast<uint16_t>(std::max(frame, 0)));
	return index;
}

uint16_t CKeyframeMap::runFrame(uint16_t run) const
{
	if (run >= m_runs.size())
		throw std::out_of_range(std::string(kClass) + ": no run " + std::to_string(run) + " (" + std::to_string(m_runs.size()) + " runs)");
	return m_runFrame[run];
}

void CKeyframeMap::reportLoadProblems(std::ostream& out, const std::string& path) const
{
	for (const auto& p : m_loadProblems) out << "warning: map '" << path << "': " << p << "\n";
}

uint32_t CKeyframeMap::frameOf(uint32_t id) const { return m_runFrame[keyframe(id).run]; }

void CKeyframeMap::addLink(const map::TExperienceLink& link)
{
	const auto name = [&](uint32_t id) { return "keyframe " + std::to_string(id); };
	if (link.a >= m_keyframes.size() || link.b >= m_keyframes.size())
		throw std::out_of_range(
			std::string(kClass) + "::addLink: " + name(link.a) + " to " + name(link.b) + ": the map has " +
			std::to_string(m_keyframes.size()) + " keyframes");
	if (m_keyframes[link.a].run == m_keyframes[link.b].run)
		throw std::invalid_argument(
			std::string(kClass) + "::addLink: " + name(link.a) + " and " + name(link.b) + " are of one run ('" +
			m_runs[m_keyframes[link.a].run] + "'): links join experiences");
	if (!link.T_a_b.matrix().allFinite() || !link.cov.allFinite())
		throw std::invalid_argument(std::string(kClass) + "::addLink: " + name(link.a) + " to " + name(link.b) + " not finite");
	m_links.push_back(link);
}

std::optional<map::TRelativePose> CKeyframeMap::measuredRelativePose(uint32_t a, uint32_t b) const
{
	if (sameSegment(a, b)) return relativePose(a, b);
	// The link between the two segments with the shortest chains on either side.
	const map::TExperienceLink* best = nullptr;
	bool flipped = false;
	double bestLen = std::numeric_limits<double>::infinity();
	for (const auto& l : m_links)
		for (const bool flip : {false, true})
		{
			const uint32_t la = flip ? l.b : l.a, lb = flip ? l.a : l.b;
			if (!sameSegment(a, la) || !sameSegment(lb, b)) continue;
			const double len = std::abs(m_chainDist[a] - m_chainDist[la]) + std::abs(m_chainDist[lb] - m_chainDist[b]);
			if (len < bestLen)
			{
				bestLen = len;
				best = &l;
				flipped = flip;
			}
		}
	if (!best) return std::nullopt;
	geometry::TPoseWithCov link{best->T_a_b, best->cov};
	if (flipped) link = geometry::inverse(link);
	const uint32_t la = flipped ? best->b : best->a, lb = flipped ? best->a : best->b;
	const auto ra = relativePose(a, la), rb = relativePose(lb, b);
	const auto c = geometry::compose(geometry::compose({ra.T_a_b, ra.cov}, link), {rb.T_a_b, rb.cov});
	map::TRelativePose r;
	r.T_a_b = c.T;
	r.cov = c.cov;
	r.chain_length_m = bestLen;
	return r;
}

bool CKeyframeMap::quantise(features::TStereoMeasurement& m, const map::TChannelParams& ch) const
{
	const double q = kPixelQuantum;
	const long uL = std::lround(m.uL * q), v = std::lround(m.v * q), d = std::lround((m.uL - m.uR) * q);
	if (uL < 0 || uL > 65535 || v < 0 || v > 65535 || d < -32768 || d > 32767)
		throw std::out_of_range(
			std::string(kClass) + ": measurement (uL " + std::to_string(m.uL) + ", v " + std::to_string(m.v) +
			", uR " + std::to_string(m.uR) + ") cannot be stored");
	m.uL = static_cast<float>(uL) / kPixelQuantum;
	m.v = static_cast<float>(v) / kPixelQuantum;
	m.uR = m.uL - static_cast<float>(d) / kPixelQuantum;
	m.response = static_cast<float>(std::clamp<long>(std::lround(m.response), 0, 65535));
	m.zncc = static_cast<float>(std::clamp<long>(std::lround(m.zncc * 127.f), -127, 127)) / 127.f;
	for (auto& p : m.patch) p = dequantisePixel(static_cast<uint8_t>(p >> (8 - options.patch_bits)), options.patch_bits);
	if (!normalFromCode(normalCode(m.normal), m.normal)) m.normal.setZero();  // not unit: unknown
	// As stored (idempotent: a stored sigma codes to itself); beyond the
	// code's range the pair's own model, not a clipped sigma.
	if (m.sigma_d > 0)
		m.sigma_d = m.sigma_d < 255 * kDisparitySigmaStep ? disparitySigmaFromCode(disparitySigmaCode(m.sigma_d)) : 0.f;
	Eigen::Matrix3d J;
	if (!m_calib.triangulate(m.uL, m.v, m.uR, m.P, &J)) return false;
	m.cov = m_calib.triangulationCovariance(J, ch.sigma_px, withStorageRounding(m.sigma_d));
	return true;
}

void CKeyframeMap::appendKeyframe(map::TMapKeyframe kf)
{
	if (m_channels.empty()) throw std::logic_error(std::string(kClass) + "::appendKeyframe: setup() first");
	if (kf.channels.size() != m_channels.size())
		throw std::invalid_argument(
			std::string(kClass) + "::appendKeyframe: " + std::to_string(kf.channels.size()) +
			" channels of measurements, the map has " + std::to_string(m_channels.size()));
	if (kf.run >= m_runs.size())
		throw std::invalid_argument(std::string(kClass) + "::appendKeyframe: unknown run " + std::to_string(kf.run));
	if (!m_keyframes.empty() && kf.segment < m_keyframes.back().segment)
		throw std::invalid_argument(std::string(kClass) + "::appendKeyframe: segments must not decrease");
	if (m_keyframes.size() >= 0xffffffffu) throw std::length_error(std::string(kClass) + ": too many keyframes");
	for (size_t c = 0; c < kf.channels.size(); c++)
	{
		auto& ms = kf.channels[c];
		size_t k = 0;
		for (auto& m : ms)
			if (quantise(m, m_channels[c])) ms[k++] = m;
		ms.resize(k);
	}
	kf.id = static_cast<uint32_t>(m_keyframes.size());
	const bool segStart = m_keyframes.empty() || m_keyframes.back().segment != kf.segment ||
						  m_keyframes.back().run != kf.run;
	m_chainDist.push_back(segStart ? 0.0 : m_chainDist.back() + kf.T_prev_kf.translation().norm());
	m_keyframes.push_back(std::move(kf));
	indexKeyframe(m_keyframes.back().id);
}

// ============================================================================
// Queries
// ============================================================================
const map::TMapKeyframe& CKeyframeMap::keyframe(uint32_t id) const
{
	if (id >= m_keyframes.size())
		throw std::out_of_range(
			std::string(kClass) + ": no keyframe " + std::to_string(id) + " (" + std::to_string(m_keyframes.size()) +
			" keyframes)");
	return m_keyframes[id];
}

size_t CKeyframeMap::channelIndex(const std::string& label) const
{
	std::string have;
	for (size_t i = 0; i < m_channels.size(); i++)
	{
		if (m_channels[i].label == label) return i;
		have += (i ? ", " : "") + m_channels[i].label;
	}
	throw std::out_of_range(std::string(kClass) + ": no channel '" + label + "' (the map has: " + have + ")");
}

uint64_t CKeyframeMap::cellKey(const Eigen::Vector3d& p) const
{
	auto c = [&](double x) {
		const int64_t i = static_cast<int64_t>(std::floor(x / options.index_cell_m));
		return static_cast<uint64_t>(std::clamp<int64_t>(i, -(1 << 20), (1 << 20) - 1) + (1 << 20)) & 0x1fffff;
	};
	return (c(p.x()) << 42) | (c(p.y()) << 21) | c(p.z());
}

void CKeyframeMap::indexKeyframe(uint32_t id) { m_grid[cellKey(m_keyframes[id].T_map_kf.translation())].push_back(id); }

void CKeyframeMap::rebuildIndex()
{
	m_grid.clear();
	for (uint32_t i = 0; i < m_keyframes.size(); i++) indexKeyframe(i);
}

std::vector<map::TKeyframeHit> CKeyframeMap::nearestKeyframes(
	const Eigen::Isometry3d& T_map_query, const map::TNearestQuery& q) const
{
	std::vector<map::TKeyframeHit> hits;
	if (m_keyframes.empty() || q.max_results == 0) return hits;
	const Eigen::Vector3d p = T_map_query.translation();
	const Eigen::Vector3d zq = T_map_query.linear().col(2);
	const double r = q.max_distance_m, cell = options.index_cell_m;
	const double cosMax = std::cos(q.max_angle_deg * M_PI / 180.0);
	const uint32_t frame = q.same_frame_as >= 0 ? frameOf(static_cast<uint32_t>(q.same_frame_as)) : 0;
	auto range = [&](double x) {
		return std::make_pair(
			static_cast<int64_t>(std::floor((x - r) / cell)), static_cast<int64_t>(std::floor((x + r) / cell)));
	};
	const auto [x0, x1] = range(p.x());
	const auto [y0, y1] = range(p.y());
	const auto [z0, z1] = range(p.z());
	if ((x1 - x0 + 1) * (y1 - y0 + 1) * (z1 - z0 + 1) > 100000)
		throw std::invalid_argument(
			std::string(kClass) + "::nearestKeyframes: radius " + std::to_string(r) + " m spans too many index cells");
	for (int64_t ix = x0; ix <= x1; ix++)
		for (int64_t iy = y0; iy <= y1; iy++)
			for (int64_t iz = z0; iz <= z1; iz++)
			{
				const auto it = m_grid.find(cellKey(Eigen::Vector3d((ix + 0.5) * cell, (iy + 0.5) * cell, (iz + 0.5) * cell)));
				if (it == m_grid.end()) continue;
				for (uint32_t id : it->second)
				{
					const auto& k = m_keyframes[id];
					if (k.predicted && !q.include_predicted) continue;
					if (q.same_frame_as >= 0 && frameOf(id) != frame) continue;
					const double d = (k.T_map_kf.translation() - p).norm();
					if (d > r) continue;
					const double c = std::clamp(zq.dot(k.T_map_kf.linear().col(2)), -1.0, 1.0);
					if (c < cosMax) continue;
					hits.push_back({id, d, std::acos(c) * 180.0 / M_PI});
				}
			}
	auto score = [&](const map::TKeyframeHit& h) { return h.distance_m + q.angle_weight_m_per_deg * h.angle_deg; };
	std::sort(hits.begin(), hits.end(), [&](const auto& a, const auto& b) {
		const double sa = score(a), sb = score(b);
		return sa < sb || (sa == sb && a.id < b.id);
	});
	if (hits.size() > q.max_results) hits.resize(q.max_results);
	return hits;
}

std::vector<uint32_t> CKeyframeMap::keyframesAlongChain(uint32_t id, double back_m, double ahead_m) const
{
	keyframe(id);
	uint32_t a = id, b = id;
	while (a > 0 && sameSegment(a - 1, id) && m_chainDist[id] - m_chainDist[a - 1] <= back_m) a--;
	while (b + 1 < m_keyframes.size() && sameSegment(b + 1, id) && m_chainDist[b + 1] - m_chainDist[id] <= ahead_m)
		b++;
	std::vector<uint32_t> out;
	for (uint32_t i = a; i <= b; i++) out.push_back(i);
	return out;
}

const std::vector<features::TStereoMeasurement>& CKeyframeMap::measurements(
	uint32_t id, const std::string& channel) const
{
	return keyframe(id).channels[channelIndex(channel)];
}

bool CKeyframeMap::sameSegment(uint32_t a, uint32_t b) const
{
	const auto &ka = keyframe(a), &kb = keyframe(b);
	return ka.run == kb.run && ka.segment == kb.segment;
}

double CKeyframeMap::chainDistance(uint32_t id) const
{
	keyframe(id);
	return m_chainDist[id];
}

map::TRelativePose CKeyframeMap::relativePose(uint32_t a, uint32_t b) const
{
	if (!sameSegment(a, b))
		throw std::invalid_argument(
			std::string(kClass) + "::relativePose: keyframes " + std::to_string(a) + " (segment " +
			std::to_string(m_keyframes[a].segment) + ") and " + std::to_string(b) + " (segment " +
			std::to_string(m_keyframes[b].segment) + ") are not linked by measurements (a VO break lies between)");
	map::TRelativePose r;
	const uint32_t lo = std::min(a, b), hi = std::max(a, b);
	for (uint32_t k = lo + 1; k <= hi; k++)
	{
		const auto c = geometry::compose({r.T_a_b, r.cov}, {m_keyframes[k].T_prev_kf, m_keyframes[k].cov_prev_kf});
		r.T_a_b = c.T;
		r.cov = c.cov;
	}
	r.chain_length_m = m_chainDist[hi] - m_chainDist[lo];
	if (a > b)
	{
		r.cov = geometry::invertCovariance(r.T_a_b, r.cov);
		r.T_a_b = r.T_a_b.inverse();
	}
	return r;
}

size_t CKeyframeMap::groundTruthCount() const
{
	return static_cast<size_t>(
		std::count_if(m_keyframes.begin(), m_keyframes.end(), [](const map::TMapKeyframe& k) { return k.T_gt_kf.has_value(); }));
}

size_t CKeyframeMap::stripGroundTruth()
{
	const size_t n = groundTruthCount();
	for (auto& k : m_keyframes) k.T_gt_kf.reset();
	return n;
}

double CKeyframeMap::pathLength() const
{
	double L = 0;
	for (size_t i = 1; i < m_keyframes.size(); i++)
		if (m_chainDist[i] > 0) L += m_chainDist[i] - m_chainDist[i - 1];
	return L;
}

// ============================================================================
// Serialisation
// ============================================================================
namespace
{
struct TBlocks
{
	std::vector<uint8_t> meta;
	std::vector<std::vector<uint8_t>> channels;
};
}  // namespace

static TBlocks encode(
	const TKeyframeMapOptions& o, const geometry::TStereoCalib& cal, int w, int h,
	const std::vector<map::TChannelParams>& channels, const std::vector<std::string>& runs,
	const std::vector<uint16_t>& runFrame, const std::vector<map::TExperienceLink>& links,
	const std::vector<map::TMapKeyframe>& kfs)
{
	ByteWriter m;
	putOptions(m, o);
	for (double x : {cal.fx, cal.fy, cal.cx, cal.cy, cal.cxR, cal.baseline}) m.put<double>(x);
	m.put<int32_t>(w);
	m.put<int32_t>(h);
	m.put<uint8_t>(static_cast<uint8_t>(channels.size()));
	for (const auto& c : channels) putChannel(m, c);
	m.put<uint16_t>(static_cast<uint16_t>(runs.size()));
	for (const auto& r : runs) m.str(r);
	for (const auto f : runFrame) m.put<uint16_t>(f);  // version 5
	m.put<uint32_t>(static_cast<uint32_t>(kfs.size()));
	for (const auto& k : kfs)
	{
		m.put<uint16_t>(k.run);
		m.put<uint32_t>(k.segment);
		m.put<uint64_t>(k.frame);
		m.put<double>(k.timestamp);
		m.put<uint8_t>(uint8_t(k.predicted) | uint8_t(k.T_gt_kf ? 2 : 0));
		putPose(m, k.T_map_kf);
		putPose(m, k.T_prev_kf);
		putCov(m, k.cov_prev_kf);
		if (k.T_gt_kf) putPose(m, *k.T_gt_kf);
	}
	// version 5
	m.put<uint32_t>(static_cast<uint32_t>(links.size()));
	for (const auto& l : links)
	{
		m.put<uint32_t>(l.a);
		m.put<uint32_t>(l.b);
		putPose(m, l.T_a_b);
		putCov(m, l.cov);
	}
	TBlocks b;
	b.meta = std::move(m.buf);
	// Channel blocks, column by column within a keyframe: like values sit
	// together, which compresses better than measurement by measurement.
	const double q = CKeyframeMap::kPixelQuantum;
	for (size_t c = 0; c < channels.size(); c++)
	{
		ByteWriter x;
		for (const auto& k : kfs)
		{
			const auto& ms = k.channels[c];
			x.put<uint32_t>(static_cast<uint32_t>(ms.size()));
			for (const auto& mm : ms) x.put<uint16_t>(static_cast<uint16_t>(std::lround(mm.uL * q)));
			for (const auto& mm : ms) x.put<uint16_t>(static_cast<uint16_t>(std::lround(mm.v * q)));
			for (const auto& mm : ms) x.put<int16_t>(static_cast<int16_t>(std::lround((mm.uL - mm.uR) * q)));
			for (const auto& mm : ms) x.put<uint16_t>(static_cast<uint16_t>(mm.response));
			for (const auto& mm : ms) x.put<int8_t>(static_cast<int8_t>(std::lround(mm.zncc * 127.f)));
			for (const auto& mm : ms) x.bytes(mm.desc.w.data(), 32);
			for (const auto& mm : ms)
			{
				// Horizontal differences (PNG's "Sub" filter): neighbouring pixels
				// are alike, their differences compress.
				// Only the kept top bits (patch_bits) are stored.
				const int sh = 8 - o.patch_bits;
				uint8_t row[features::kPatchSize * features::kPatchSize];
				for (int i = 0; i < features::kPatchSize * features::kPatchSize; i++)
					row[i] = (i % features::kPatchSize) ? uint8_t((mm.patch[i] >> sh) - (mm.patch[i - 1] >> sh))
														: uint8_t(mm.patch[i] >> sh);
				x.bytes(row, sizeof(row));
			}
			for (const auto& mm : ms)
			{
				const auto nc = normalCode(mm.normal);
				x.bytes(nc.data(), nc.size());
			}
			for (const auto& mm : ms) x.put<uint8_t>(disparitySigmaCode(mm.sigma_d));	// version 6
		}
		b.channels.push_back(std::move(x.buf));
	}
	return b;
}

// 0: channels recorded as a kind (mono / invariant) with the invariant
//    parameters, before channels were filters; refused (no map of it was kept).
// 1: channels recorded as the filter that made them (class, image options).
// 2: the options' landmark selection (policy, re-observation window and
//    radius, minimum re-observations) after the version 1 options; a
//    version 1 map reads as thinned by the strongest corners.
// 3: each channel block's checksum covers its position (blockSum): blocks
//    swapped between channels fail the load.
// 4: a surface normal per measurement (3 x int8 after the patches), for
//    warped matching; each channel records its descriptor kind (FAST +
//    BRIEF or ORB) and ORB's pyramid (levels, scale factor). Maps of
//    versions 1-3 load without normals, as BRIEF.
// 5: experiences: after the run names a flag per run (anchored in the map
//    frame or in its own), after the keyframes the links between runs
//    (keyframe ids, T_a_b, covariance). Maps of versions 1-4 load as one
//    anchored run per name, without links.
// 6: the options' depth_from_reobservations; after the normals a refined
//    disparity's sigma per measurement (uint8, 1/128 px, 0 = the pair's own
//    depth). Maps of versions 1-5 load with every depth the pair's.
uint8_t CKeyframeMap::serializeGetVersion() const { return 6; }

void CKeyframeMap::serializeTo(mrpt::serialization::CArchive& out) const
{
	const TBlocks b = encode(options, m_calib, m_width, m_height, m_channels, m_runs, m_runFrame, m_links, m_keyframes);
	std::vector<const std::vector<uint8_t>*> blocks{&b.meta};
	for (const auto& c : b.channels) blocks.push_back(&c);
	out << static_cast<uint8_t>(blocks.size());
	for (size_t i = 0; i < blocks.size(); i++)
	{
		const auto* raw = blocks[i];
		const auto comp = compressBlock(*raw, options.compression_level);
		out << static_cast<uint64_t>(raw->size()) << static_cast<uint64_t>(comp.size()) << blockSum(comp, i);
		out.WriteBuffer(comp.data(), comp.size());
	}
}

void CKeyframeMap::serializeFrom(mrpt::serialization::CArchive& in, uint8_t version)
{
	switch (version)
	{
		case 0:
			throw std::runtime_error(
				std::string(kClass) +
				": format version 0 (channels stored as mono/invariant kinds) is no longer read; rebuild the map "
				"with `shadyloc survey`");
		case 1:
		case 2:
		case 3:
		case 4:
		case 5:
		case 6:
		{
			// The stream's size is unknown here: the budget is the largest map
			// (kMaxSerializedBytes); offsets count from the object's data.
			io::BoundedReader in_(
				in, std::string(kClass) + " (version " + std::to_string(version) + ")", kMaxSerializedBytes);
			const auto nBlocks = in_.read<uint8_t>("block count");
			if (nBlocks < 1 || nBlocks > kMaxChannels + 1)
				in_.fail("block count", std::to_string(nBlocks) + " blocks: 1 + channels (at most " +
											std::to_string(kMaxChannels) + ") expected");
			std::vector<std::vector<uint8_t>> raw;
			for (int i = 0; i < nBlocks; i++)
			{
				const std::string what = std::string(kClass) + " block " + std::to_string(i);
				const auto rawSize = in_.read<uint64_t>("block raw size");
				const auto compSize = in_.read<uint64_t>("block stored size");
				const auto sum = in_.read<uint64_t>("block checksum");
				if (rawSize > kMaxSerializedBytes)
					in_.fail("block raw size", std::to_string(rawSize) + " bytes: beyond any map (damaged)");
				const auto comp = readBlob(in_, compSize, "block data");
				if (blockSum(comp, version >= 3 ? static_cast<size_t>(i) : 0) != sum)
					throw io::CorruptDataError(what + ": checksum mismatch (damaged, or a block moved from another position)");
				raw.push_back(decompressBlock(comp, rawSize, what));
			}
			// Parse into locals, then swap in: a failed load leaves the map as it was.
			ByteReader r(raw[0].data(), raw[0].size(), std::string(kClass) + " metadata");
			TKeyframeMapOptions o = getOptions(r, version);
			geometry::TStereoCalib cal;
			for (double* x : {&cal.fx, &cal.fy, &cal.cx, &cal.cy, &cal.cxR, &cal.baseline})
			{
				*x = r.get<double>();
				if (!std::isfinite(*x)) r.fail("calibration not finite");
			}
			if (!(cal.fx > 0 && cal.fy > 0 && cal.baseline > 0)) r.fail("calibration: fx, fy, baseline must be > 0");
			const int w = r.get<int32_t>(), h = r.get<int32_t>();
			const auto nc = r.get<uint8_t>();
			if (nc > kMaxChannels || nc + 1 != nBlocks)
				r.fail(std::to_string(nc) + " channels for " + std::to_string(nBlocks) + " blocks");
			// A map that was never set up (no channels, image size 0) holds no keyframes.
			const bool setUp = nc > 0;
			if (setUp ? (w <= 0 || h <= 0 || w * kPixelQuantum > 65535 || h * kPixelQuantum > 65535) : (w != 0 || h != 0))
				r.fail("image size " + std::to_string(w) + "x" + std::to_string(h));
			std::vector<map::TChannelParams> channels;
			for (int i = 0; i < nc; i++) channels.push_back(getChannel(r, version));
			const auto nr = r.get<uint16_t>();
			std::vector<std::string> runs;
			for (int i = 0; i < nr; i++) runs.push_back(r.str());
			std::vector<uint16_t> frames(nr, 0);
			std::vector<std::string> problems;	// left out, reported; the rest loads
			if (version >= 5)
				for (int i = 0; i < nr; i++)
				{
					// 0, itself (a frame of its own) or an earlier run that founded its frame.
					frames[i] = r.get<uint16_t>();
					if (frames[i] > i || (frames[i] > 0 && frames[frames[i]] != frames[i]))
					{
						problems.push_back(
							"run " + std::to_string(i) + " ('" + runs[i] + "'): its frame names run " +
							std::to_string(frames[i]) + ", which founds none: kept in a frame of its own, unlinked");
						frames[i] = static_cast<uint16_t>(i);
					}
				}
			const auto nk = r.get<uint32_t>();
			if (!setUp && nk > 0) r.fail(std::to_string(nk) + " keyframes in a map without channels");
			r.requireItems(nk, 2 + 4 + 8 + 8 + 1 + 2 * 96 + 21 * 8, "keyframe");
			CKeyframeMap tmp;
			tmp.options = o;
			tmp.m_calib = cal;
			tmp.m_width = w;
			tmp.m_height = h;
			tmp.m_channels = channels;
			tmp.m_runs = runs;
			tmp.m_runFrame = frames;
			std::vector<map::TMapKeyframe> kfs(nk);
			for (uint32_t i = 0; i < nk; i++)
			{
				auto& k = kfs[i];
				k.run = r.get<uint16_t>();
				if (k.run >= runs.size()) r.fail("keyframe " + std::to_string(i) + ": run " + std::to_string(k.run));
				k.segment = r.get<uint32_t>();
				if (i > 0 && k.segment < kfs[i - 1].segment) r.fail("keyframe " + std::to_string(i) + ": segment decreases");
				k.frame = r.get<uint64_t>();
				k.timestamp = r.get<double>();
				const auto flags = r.get<uint8_t>();
				if (flags > 3) r.fail("keyframe " + std::to_string(i) + ": flags");
				k.predicted = flags & 1;
				k.T_map_kf = getPose(r, "T_map_kf");
				k.T_prev_kf = getPose(r, "T_prev_kf");
				k.cov_prev_kf = getCov(r);
				if (flags & 2) k.T_gt_kf = getPose(r, "T_gt_kf");
				k.channels.resize(nc);
			}
			std::vector<map::TExperienceLink> links;
			if (version >= 5)
			{
				const auto nl = r.get<uint32_t>();
				r.requireItems(nl, 4 + 4 + 96 + 21 * 8, "link");
				for (uint32_t i = 0; i < nl; i++)
				{
					map::TExperienceLink l;
					l.a = r.get<uint32_t>();
					l.b = r.get<uint32_t>();
					l.T_a_b = readPose(r);
					l.cov = readCov(r);
					const std::string why = brokenLink(l, kfs, frames);
					if (why.empty())
						links.push_back(l);
					else
						problems.push_back(
							"link " + std::to_string(i) + " (keyframes " + std::to_string(l.a) + ", " + std::to_string(l.b) +
							"): " + why + ": left out");
				}
			}
			tmp.m_links = std::move(links);
			std::vector<bool> runHasKeyframes(nr, false);
			for (const auto& k : kfs) runHasKeyframes[k.run] = true;
			for (uint16_t i = 0; i < nr; i++)
				if (!runHasKeyframes[i])
					problems.push_back("run " + std::to_string(i) + " ('" + runs[i] + "'): no keyframe (a missing experience)");
			tmp.m_loadProblems = std::move(problems);
			if (r.remaining()) r.fail(std::to_string(r.remaining()) + " bytes left over");
			for (int c = 0; c < nc; c++)
			{
				ByteReader x(raw[c + 1].data(), raw[c + 1].size(), std::string(kClass) + " channel '" + channels[c].label + "'");
				for (uint32_t i = 0; i < nk; i++)
				{
					const auto n = x.get<uint32_t>();
					x.requireItems(
						n, kMeasBytes + (version >= 4 ? kNormalBytes : 0) + (version >= 6 ? kDisparitySigmaBytes : 0),
						"measurement");
					auto& ms = kfs[i].channels[c];
					ms.resize(n);
					for (auto& m : ms) m.uL = static_cast<float>(x.get<uint16_t>()) / kPixelQuantum;
					for (auto& m : ms) m.v = static_cast<float>(x.get<uint16_t>()) / kPixelQuantum;
					for (auto& m : ms) m.uR = m.uL - static_cast<float>(x.get<int16_t>()) / kPixelQuantum;
					for (auto& m : ms) m.response = x.get<uint16_t>();
					for (auto& m : ms)
					{
						const auto z = x.get<int8_t>();
						if (z < -127) x.fail("zncc out of range");
						m.zncc = static_cast<float>(z) / 127.f;
					}
					for (auto& m : ms) x.bytes(m.desc.w.data(), 32);
					for (auto& m : ms)
					{
						x.bytes(m.patch.data(), m.patch.size());
						for (size_t j = 0; j < m.patch.size(); j++)
							if (j % features::kPatchSize) m.patch[j] = uint8_t(m.patch[j] + m.patch[j - 1]);
						const int maxQ = (1 << o.patch_bits) - 1;
						for (auto& p : m.patch)
						{
							if (p > maxQ) x.fail("patch pixel beyond patch_bits " + std::to_string(o.patch_bits));
							p = dequantisePixel(p, o.patch_bits);
						}
					}
					if (version >= 4)
						for (auto& m : ms)
						{
							std::array<int8_t, 3> nc;
							x.bytes(nc.data(), nc.size());
							if (!normalFromCode(nc, m.normal)) x.fail("surface normal not of unit length");
						}
					if (version >= 6)
						for (auto& m : ms) m.sigma_d = disparitySigmaFromCode(x.get<uint8_t>());
					for (size_t j = 0; j < ms.size(); j++)
					{
						Eigen::Matrix3d J;
						if (!cal.triangulate(ms[j].uL, ms[j].v, ms[j].uR, ms[j].P, &J))
							x.fail("keyframe " + std::to_string(i) + " measurement " + std::to_string(j) + " does not triangulate");
						ms[j].cov = cal.triangulationCovariance(J, channels[c].sigma_px, withStorageRounding(ms[j].sigma_d));
					}
				}
				if (x.remaining()) x.fail(std::to_string(x.remaining()) + " bytes left over");
			}
			for (auto& k : kfs) tmp.appendLoaded(std::move(k));
			*this = std::move(tmp);
		}
		break;
		default: MRPT_THROW_UNKNOWN_SERIALIZATION_VERSION(version);
	}
}

void CKeyframeMap::appendLoaded(map::TMapKeyframe kf)
{
	kf.id = static_cast<uint32_t>(m_keyframes.size());
	const bool segStart = m_keyframes.empty() || m_keyframes.back().segment != kf.segment ||
						  m_keyframes.back().run != kf.run;
	m_chainDist.push_back(segStart ? 0.0 : m_chainDist.back() + kf.T_prev_kf.translation().norm());
	m_keyframes.push_back(std::move(kf));
	indexKeyframe(m_keyframes.back().id);
}

CKeyframeMap::TSizeReport CKeyframeMap::sizeReport() const
{
	TSizeReport s;
	const TBlocks b = encode(options, m_calib, m_width, m_height, m_channels, m_runs, m_runFrame, m_links, m_keyframes);
	s.meta_bytes = compressBlock(b.meta, options.compression_level).size();
	for (size_t c = 0; c < b.channels.size(); c++)
	{
		s.channel_raw_bytes.push_back(b.channels[c].size());
		s.channel_bytes.push_back(compressBlock(b.channels[c], options.compression_level).size());
		size_t n = 0;
		for (const auto& k : m_keyframes) n += k.channels[c].size();
		s.channel_measurements.push_back(n);
	}
	mrpt::io::CMemoryStream mem;
	auto ar = mrpt::serialization::archiveFrom(mem);
	ar << *this;
	s.total_bytes = mem.getTotalBytesCount();
	return s;
}

// ============================================================================
// Files
// ============================================================================
void CKeyframeMap::saveToFile(const std::string& path, const std::function<void(size_t)>& afterChunk) const
{
	mrpt::io::CMemoryStream mem;
	auto ar = mrpt::serialization::archiveFrom(mem);
	ar << *this;
	const auto* data = static_cast<const uint8_t*>(mem.getRawBufferData());
	const size_t n = mem.getTotalBytesCount();
	io::writeAtomically(path, [&](const std::string& tmp) {
		const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
		if (fd < 0) throw std::runtime_error("cannot create '" + tmp + "' (for '" + path + "')");
		size_t done = 0;
		const size_t kChunk = 64 << 10;
		while (done < n)
		{
			const ssize_t k = ::write(fd, data + done, std::min(kChunk, n - done));
			if (k <= 0)
			{
				::close(fd);
				throw std::runtime_error("cannot write '" + tmp + "' (for '" + path + "'): disk full?");
			}
			done += static_cast<size_t>(k);
			if (afterChunk) afterChunk(done);
		}
		// On disk before the rename makes it the map: a crash leaves the old file or the new one.
		if (::fsync(fd) != 0 || ::close(fd) != 0) throw std::runtime_error("cannot flush '" + tmp + "'");
	});
}

namespace
{
/** MRPT's object header: 0x80 | name length, the class name, the version.
 * ReadObject(existing) does not compare the name, so check it here: a file
 * of another class is refused before anything of it is parsed. */
void checkObjectHeader(const uint8_t* data, size_t size, const std::string& path)
{
	if (size == 0) throw std::runtime_error("keyframe map '" + path + "': empty file");
	const std::string name = kClass;
	const size_t nameLen = data[0] & 0x7f;
	const std::string stored(reinterpret_cast<const char*>(data) + 1, std::min(nameLen, size - 1));
	if ((data[0] & 0x80) == 0 || stored != name)
		throw std::runtime_error(
			"keyframe map '" + path + "': holds " +
			((data[0] & 0x80) && nameLen == stored.size() ? "a '" + stored + "' object" : std::string("no MRPT object")) +
			", not a " + name);
}

/** Exactly `n` bytes of `f` from its current position, or an error naming `path`. */
void readExactly(std::ifstream& f, uint8_t* to, size_t n, const std::string& path)
{
	f.read(reinterpret_cast<char*>(to), static_cast<std::streamsize>(n));
	if (static_cast<size_t>(f.gcount()) != n)
		throw std::runtime_error("keyframe map '" + path + "': cannot read (the file is shorter than its size)");
}

/** The bytes of a map file: a regular file only (/dev/zero or a FIFO would
 * be read until memory ran out), its header checked before the rest is
 * read, exactly its size read. */
std::vector<uint8_t> readMapFile(const std::string& path)
{
	std::error_code ec;
	const auto st = fs::status(path, ec);
	if (ec || !fs::exists(st)) throw std::runtime_error("keyframe map '" + path + "': cannot open (no such file)");
	if (!fs::is_regular_file(st))
		throw std::runtime_error("keyframe map '" + path + "': not a regular file (a directory, device or pipe)");
	const uint64_t size = fs::file_size(path, ec);
	if (ec) throw std::runtime_error("keyframe map '" + path + "': cannot open (" + ec.message() + ")");
	if (size > kMaxSerializedBytes + 256)  // the object's data, MRPT's header and end byte
		throw std::runtime_error("keyframe map '" + path + "': " + std::to_string(size) + " bytes, beyond any map");
	std::ifstream f(path, std::ios::binary);
	if (!f) throw std::runtime_error("keyframe map '" + path + "': cannot open");
	// The header first: a file of something else is refused unread.
	const size_t head = static_cast<size_t>(std::min<uint64_t>(size, 128));
	std::vector<uint8_t> bytes(head);
	readExactly(f, bytes.data(), head, path);
	checkObjectHeader(bytes.data(), head, path);
	bytes.resize(size);
	readExactly(f, bytes.data() + head, size - head, path);
	return bytes;
}
}  // namespace

CKeyframeMap::Ptr CKeyframeMap::LoadFromFile(const std::string& path)
{
	const auto bytes = readMapFile(path);
	return LoadFromBytes(bytes.data(), bytes.size(), path);
}

CKeyframeMap::Ptr CKeyframeMap::LoadFromBytes(const uint8_t* data, size_t size, const std::string& path)
{
	checkObjectHeader(data, size, path);
	// Read in place: a copy cost a damaged file twice its size in memory.
	mrpt::io::CMemoryStream mem;
	mem.assignMemoryNotOwn(data, size);
	auto ar = mrpt::serialization::archiveFrom(mem);
	auto map = CKeyframeMap::Create();
	try
	{
		// Checks the stored class name against ours before reading anything of
		// the object, so a file of another class is refused, not parsed.
		ar.ReadObject(map.get());
	}
	catch (const std::exception& e)
	{
		// MRPT wraps the reader's error in its own message with a call trace.
		const std::string why = core::mrptReason(mrpt::exception_to_str(e));
		throw std::runtime_error(
			"keyframe map '" + path + "': cannot be read (damaged, or not a " + kClass + " file): " + why);
	}
	if (mem.getPosition() != size)
		throw std::runtime_error(
			"keyframe map '" + path + "': " + std::to_string(size - mem.getPosition()) +
			" unexpected bytes after the map");
	return map;
}

void CKeyframeMap::saveMetricMapRepresentationToFile(const std::string& prefix) const
{
	saveToFile(prefix + kFileExtension);
	io::writeAtomically(prefix + "_keyframes.tum", [&](const std::string& tmp) {
		std::ofstream f(tmp);
		f << "# keyframes of " << kClass << ": timestamp, left camera in the map frame (TUM)\n"
		  << std::setprecision(9);
		for (const auto& k : m_keyframes)
		{
			const Eigen::Quaterniond q(k.T_map_kf.linear());
			const auto& t = k.T_map_kf.translation();
			f << k.timestamp << ' ' << t.x() << ' ' << t.y() << ' ' << t.z() << ' ' << q.x() << ' ' << q.y() << ' '
			  << q.z() << ' ' << q.w() << '\n';
		}
		if (!f) throw std::runtime_error("cannot write '" + tmp + "'");
	});
}

// ============================================================================
// CMetricMap
// ============================================================================
void CKeyframeMap::internal_clear()
{
	m_keyframes.clear();
	m_chainDist.clear();
	m_grid.clear();
	m_runs.clear();
	m_runFrame.clear();
	m_links.clear();
	m_loadProblems.clear();
}

bool CKeyframeMap::internal_insertObservation(
	const mrpt::obs::CObservation& obs, const std::optional<const mrpt::poses::CPose3D>&)
{
	throw std::logic_error(
		std::string(kClass) + "::insertObservation(" + obs.GetRuntimeClass()->className +
		"): keyframes come from a VO chain; build maps with map::SurveyBuilder (`shadyloc survey`)");
}

double CKeyframeMap::internal_computeObservationLikelihood(
	const mrpt::obs::CObservation& obs, const mrpt::poses::CPose3D&) const
{
	throw std::logic_error(
		std::string(kClass) + "::computeObservationLikelihood(" + obs.GetRuntimeClass()->className +
		"): not defined for a keyframe map; localisers use its map::KeyframeQueries interface");
}

void CKeyframeMap::determineMatching2D(
	const mrpt::maps::CMetricMap*, const mrpt::poses::CPose2D&, mrpt::tfest::TMatchingPairList&,
	const mrpt::maps::TMatchingParams&, mrpt::maps::TMatchingExtraResults&) const
{
	throw std::logic_error(std::string(kClass) + "::determineMatching2D: not defined for a keyframe map");
}
void CKeyframeMap::determineMatching3D(
	const mrpt::maps::CMetricMap*, const mrpt::poses::CPose3D&, mrpt::tfest::TMatchingPairList&,
	const mrpt::maps::TMatchingParams&, mrpt::maps::TMatchingExtraResults&) const
{
	throw std::logic_error(std::string(kClass) + "::determineMatching3D: not defined for a keyframe map");
}
float CKeyframeMap::compute3DMatchingRatio(
	const mrpt::maps::CMetricMap*, const mrpt::poses::CPose3D&, const mrpt::maps::TMatchingRatioParams&) const
{
	throw std::logic_error(std::string(kClass) + "::compute3DMatchingRatio: not defined for a keyframe map");
}
float CKeyframeMap::squareDistanceToClosestCorrespondence(float, float) const
{
	throw std::logic_error(std::string(kClass) + "::squareDistanceToClosestCorrespondence: not defined for a keyframe map");
}

void CKeyframeMap::getVisualizationInto(mrpt::opengl::CSetOfObjects& o) const { getVisualizationInto(o, TDrawStyle()); }

void CKeyframeMap::getVisualizationInto(mrpt::opengl::CSetOfObjects& o, const TDrawStyle& style) const
{
	if (!genericMapParams.enableSaveAs3DObject || m_keyframes.empty()) return;
	// Only the map frame's keyframes: an experience kept in a frame of its
	// own has poses unrelated to it (drawn here it would lie over the others).
	const auto inMapFrame = [&](const map::TMapKeyframe& k) { return m_runFrame[k.run] == 0; };
	Eigen::Vector3d lo = m_keyframes[0].T_map_kf.translation(), hi = lo;
	for (const auto& k : m_keyframes)
	{
		if (!inMapFrame(k)) continue;
		lo = lo.cwiseMin(k.T_map_kf.translation());
		hi = hi.cwiseMax(k.T_map_kf.translation());
	}
	const double width = style.path_width_m > 0 ? style.path_width_m : std::max(0.05, (hi - lo).norm() / 250);
	const double marker = style.marker_size_m > 0 ? style.marker_size_m : 4 * width;
	const mrpt::img::TColor measured = kDrawColourMeasured, predicted = kDrawColourPredicted;
	auto tri = [](mrpt::opengl::CSetOfTriangles& t, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
				  const Eigen::Vector3d& c, const mrpt::img::TColor& col) {
		mrpt::opengl::TTriangle x(
			mrpt::math::TPoint3Df(float(a.x()), float(a.y()), float(a.z())),
			mrpt::math::TPoint3Df(float(b.x()), float(b.y()), float(b.z())),
			mrpt::math::TPoint3Df(float(c.x()), float(c.y()), float(c.z())));
		for (auto& v : x.vertices) v.setColor(col);
		t.insertTriangle(x);
	};
	// The path: one ribbon per link within a segment, in the road plane (the
	// plane of the camera's x and z axes; its y axis points down), each quad
	// extended by half a width so the joints overlap instead of notching.
	auto path = mrpt::opengl::CSetOfTriangles::Create();
	path->enableLight(false);
	for (size_t i = 0; i + 1 < m_keyframes.size(); i++)
	{
		if (!sameSegment(static_cast<uint32_t>(i), static_cast<uint32_t>(i + 1)) || !inMapFrame(m_keyframes[i])) continue;
		const auto& ka = m_keyframes[i];
		const Eigen::Vector3d a = ka.T_map_kf.translation(), b = m_keyframes[i + 1].T_map_kf.translation();
		Eigen::Vector3d d = b - a;
		if (d.norm() < 1e-9) continue;
		d.normalize();
		Eigen::Vector3d side = d.cross(ka.T_map_kf.linear().col(1));
		if (side.norm() < 1e-6) continue;  // moving straight up or down: no road plane
		side = side.normalized() * (0.5 * width);
		const Eigen::Vector3d e = d * (0.5 * width);
		const auto& col = m_keyframes[i + 1].predicted ? predicted : measured;
		tri(*path, a - e + side, a - e - side, b + e - side, col);
		tri(*path, a - e + side, b + e - side, b + e + side, col);
	}
	o.insert(path);
	// Keyframe markers: chevrons in the road plane pointing along the view.
	auto marks = mrpt::opengl::CSetOfTriangles::Create();
	marks->enableLight(false);
	double last = -1e18;
	for (size_t i = 0; i < m_keyframes.size(); i++)
	{
		const auto& k = m_keyframes[i];
		if (!inMapFrame(k) || (m_chainDist[i] != 0 && m_chainDist[i] - last < options.draw_frame_every_m)) continue;
		last = m_chainDist[i];
		const Eigen::Vector3d p = k.T_map_kf.translation(), down = k.T_map_kf.linear().col(1);
		Eigen::Vector3d f = k.T_map_kf.linear().col(2);
		f = (f - f.dot(down) * down).normalized();
		const Eigen::Vector3d r = f.cross(down).normalized();
		// Lifted a little off the road plane (towards -down) so they lie on the path.
		const Eigen::Vector3d q = p - 0.02 * marker * down;
		const mrpt::img::TColor col = k.predicted ? mrpt::img::TColor(150, 70, 0) : mrpt::img::TColor(10, 25, 110);
		tri(*marks, q + f * marker, q - 0.6 * marker * f + 0.5 * marker * r, q - 0.3 * marker * f, col);
		tri(*marks, q + f * marker, q - 0.3 * marker * f, q - 0.6 * marker * f - 0.5 * marker * r, col);
	}
	o.insert(marks);
	if (options.draw_landmarks)
	{
		for (size_t c = 0; c < m_channels.size(); c++)
		{
			auto pc = mrpt::opengl::CPointCloudColoured::Create();
			pc->setPointSize(3);
			const mrpt::img::TColorf col(drawColourOfChannel(c));
			for (const auto& k : m_keyframes)
				for (const auto& m : k.channels[c])
				{
					if (!inMapFrame(k) || m.P.z() > options.draw_landmark_max_depth_m) continue;
					const Eigen::Vector3d p = k.T_map_kf * m.P;
					pc->push_back(p.x(), p.y(), p.z(), col.R, col.G, col.B);
				}
			o.insert(pc);
		}
	}
}

mrpt::img::TColor CKeyframeMap::drawColourOfChannel(size_t c)
{
	static const mrpt::img::TColor colours[] = {{40, 40, 40}, {220, 30, 150}, {30, 170, 60}, {230, 150, 0}};
	return colours[c % 4];
}

std::string CKeyframeMap::asString() const
{
	std::ostringstream s;
	std::set<uint32_t> segs;
	size_t predicted = 0, gt = 0;
	for (const auto& k : m_keyframes)
	{
		segs.insert(k.segment);
		predicted += k.predicted;
		gt += bool(k.T_gt_kf);
	}
	const double L = pathLength();
	s << kClass << ": " << m_keyframes.size() << " keyframes, " << std::fixed << std::setprecision(1) << L
	  << " m of path, " << m_runs.size() << " run(s)";
	for (size_t i = 0; i < m_runs.size(); i++)
		s << (i ? ", " : " (") << "'" << m_runs[i] << "'" << (m_runFrame[i] == 0 ? "" : m_runFrame[i] == i ? " in its own frame" : " in the frame of '" + m_runs[m_runFrame[i]] + "'")
		  << (i + 1 == m_runs.size() ? ")" : "");
	s << ", " << segs.size() << " segment(s)";
	if (m_runs.size() > 1) s << ", " << m_links.size() << " link(s) between runs";
	if (predicted) s << " (" << predicted << " keyframes after VO breaks: map pose predicted)";
	s << "\n  ground truth beside " << gt << " keyframes (evaluation only)\n";
	if (!m_channels.empty())
		s << "  camera " << m_width << "x" << m_height << " px, " << m_calib.asString() << "\n";
	const bool sized = !m_keyframes.empty();
	TSizeReport sz;
	if (sized) sz = sizeReport();
	for (size_t c = 0; c < m_channels.size(); c++)
	{
		s << "  channel " << m_channels[c].asString() << "\n";
		if (sized)
		{
			const double n = sz.channel_measurements[c];
			s << std::setprecision(1) << "    " << n / m_keyframes.size() << " measurements/keyframe, "
			  << sz.channel_bytes[c] / 1e3 << " kB (" << sz.channel_bytes[c] / std::max(1.0, n) << " B/measurement, "
			  << sz.channel_bytes[c] / 1e3 / m_keyframes.size() << " kB/keyframe";
			if (L > 0) s << ", " << std::setprecision(2) << sz.channel_bytes[c] / 1e6 / (L / 1000) << " MB/km";
			s << ")\n";
		}
	}
	if (sized) s << "  stored: " << sz.total_bytes << " bytes (metadata " << sz.meta_bytes << ")\n";
	s << "  options: kf_spacing " << std::setprecision(2) << options.kf_spacing_m << " m / " << options.kf_spacing_deg
	  << " deg, landmarks_per_keyframe " << options.landmarks_per_keyframe << " ("
	  << toString(options.landmark_selection);
	if (options.landmark_selection == TKeyframeMapOptions::LandmarkSelection::Reobserved)
		s << ": window " << options.reobservation_window_m << " m, radius " << options.reobservation_radius_px
		  << " px, at least " << options.min_reobservations << " re-observations";
	s << "), zstd level " << options.compression_level << "\n  " << drawingSummary();
	return s.str();
}

// Said from the same predicates as getVisualizationInto, so a viewer's
// user (RawLogViewer shows asString beside the 3D view) knows what is and
// is not drawn, and where.
std::string CKeyframeMap::drawingSummary() const
{
	std::ostringstream s;
	s << "drawing: ";
	if (!genericMapParams.enableSaveAs3DObject || m_keyframes.empty())
		return s.str() + "nothing (" + (m_keyframes.empty() ? "no keyframes" : "enableSaveAs3DObject is off") + ")";
	size_t drawn = 0, landmarks = 0;
	for (const auto& k : m_keyframes)
	{
		if (m_runFrame[k.run] != 0) continue;
		drawn++;
		if (options.draw_landmarks)
			for (const auto& ch : k.channels)
				for (const auto& m : ch) landmarks += m.P.z() <= options.draw_landmark_max_depth_m;
	}
	s << "in the map frame (the first keyframe's left camera: x right, y down, "
	  << "z forward, origin at that camera), the keyframe chain of " << drawn
	  << " keyframes as a ribbon in the road plane (blue measured, orange predicted), a chevron at most every "
	  << options.draw_frame_every_m << " m; ";
	if (options.draw_landmarks)
		s << landmarks << " landmarks within " << options.draw_landmark_max_depth_m
		  << " m of their keyframe, coloured by channel";
	else
		s << "landmarks not drawn (draw_landmarks off)";
	if (drawn < m_keyframes.size())
		s << "; " << m_keyframes.size() - drawn << " keyframes in frames of their own not drawn";
	return s.str();
}

// ============================================================================
// Map definition (CMultiMetricMap .ini)
// ============================================================================
CKeyframeMap::TMapDefinition::TMapDefinition() = default;

void CKeyframeMap::TMapDefinition::loadFromConfigFile_map_specific(
	const mrpt::config::CConfigFileBase& source, const std::string& prefix)
{
	creationOpts.loadFromConfigFile(source, prefix + "_creationOpts");
}

void CKeyframeMap::TMapDefinition::dumpToTextStream_map_specific(std::ostream& out) const
{
	out << "[creationOpts]\n";
	creationOpts.dumpToTextStream(out);
}

mrpt::maps::CMetricMap* CKeyframeMap::internal_CreateFromMapDefinition(const mrpt::maps::TMetricMapInitializer& def)
{
	const auto& d = dynamic_cast<const CKeyframeMap::TMapDefinition&>(def);
	auto* m = new CKeyframeMap();
	m->options = d.creationOpts;
	return m;
}
