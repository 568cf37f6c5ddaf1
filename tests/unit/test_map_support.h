/* Synthetic keyframe maps for the map tests. */
#pragma once

#include <shadyloc/filters/Filters.h>
#include <shadyloc/map/CKeyframeMap.h>
#include <shadyloc/survey/SurveyBuilder.h>

#include <random>

namespace shadyloc::test
{
/** Field changed by makeSyntheticMap's `mutate` (0 = none): each value
 * changes exactly one stored field, so a round-trip comparison must see it. */
enum Mutation
{
	kNone = 0,
	kOptSpacing,
	kOptLandmarks,
	kOptDraw,
	kOptSelection,
	kOptReobservation,
	kOptPatchBits,
	kCalibFx,
	kCalibCxR,
	kImageWidth,
	kChannelLabel,
	kChannelSeed,
	kChannelPresmooth,
	kChannelSigma,
	kInvariantAlpha,
	kInvariantScale,
	kChannelFilterClass,
	kChannelDescriptor,
	kChannelOrbLevels,
	kChannelOrbScale,
	kRunName,
	kKfTimestamp,
	kKfFrame,
	kKfSegment,
	kKfPredicted,
	kKfPose,
	kKfRelPose,
	kKfCov,
	kKfGtMissing,
	kKfGtPose,
	kMeasUL,
	kMeasV,
	kMeasUR,
	kMeasResponse,
	kMeasZncc,
	kMeasDescBit,
	kMeasPatch,
	kMeasDropped,
	kMutationCount
};

/** A map of n keyframes along a gently curving road (z forward, x right),
 * spacing ~2 m, a VO break (new predicted segment) after breakAt (if > 0),
 * two channels of `perKf` random but valid measurements each. Deterministic. */
inline CKeyframeMap::Ptr makeSyntheticMap(int n = 24, int perKf = 40, int breakAt = 15, int mutate = kNone)
{
	std::mt19937 rng(42);
	std::uniform_real_distribution<double> U(0, 1);
	auto m = CKeyframeMap::Create();
	m->options.compression_level = 3;
	if (mutate == kOptSpacing) m->options.kf_spacing_m = 2.5;
	if (mutate == kOptLandmarks) m->options.landmarks_per_keyframe = 77;
	if (mutate == kOptDraw) m->options.draw_landmarks = true;
	if (mutate == kOptSelection) m->options.landmark_selection = TKeyframeMapOptions::LandmarkSelection::Strongest;
	if (mutate == kOptReobservation) m->options.reobservation_window_m = 3.5;
	m->options.patch_bits = mutate == kOptPatchBits ? 6 : 8;  // 8: the patches as drawn below
	geometry::TStereoCalib cal;
	cal.fx = cal.fy = 400;
	cal.cx = 256;
	cal.cy = 192;
	cal.cxR = 256;
	cal.baseline = 0.24;
	if (mutate == kCalibFx) cal.fx = 400.5;
	if (mutate == kCalibCxR) cal.cxR = 256.25;
	// The channels as a survey records them: the filters that made them.
	features::TStereoFeatureOptions fmono, finv;
	if (mutate == kChannelSeed) fmono.brief_seed = 7;
	finv.presmooth_sigma = mutate == kChannelPresmooth ? 1.5 : 1.0;
	if (mutate == kChannelSigma) finv.sigma_px = 0.6;
	if (mutate == kChannelDescriptor) finv.descriptor = features::DescriptorKind::Orb;
	if (mutate == kChannelOrbLevels) finv.orb_levels = 4;
	if (mutate == kChannelOrbScale) finv.orb_scale_factor = 1.3;
	CFilterMonochrome monoFilter;
	CFilterInvariant invFilter;
	auto ip = image::InvariantParams::FromWavelengths(470, 540, 620);
	ip.scale = mutate == kInvariantScale ? 127 : 128;
	if (mutate == kInvariantAlpha) ip.alpha += 1e-3;
	invFilter.setParams(ip);
	map::TChannelParams mono = survey::channelParams(mutate == kChannelLabel ? "grey" : "mono", monoFilter, fmono);
	const map::TChannelParams inv = survey::channelParams("invariant", invFilter, finv);
	if (mutate == kChannelFilterClass) mono.filter_class = "shadyloc::CFilterLinearise";
	m->setup(cal, mutate == kImageWidth ? 513 : 512, 384, {mono, inv});
	const uint16_t run = m->addRun(mutate == kRunName ? "noon2" : "noon");
	Eigen::Isometry3d T_map = Eigen::Isometry3d::Identity();
	for (int i = 0; i < n; i++)
	{
		map::TMapKeyframe k;
		k.run = run;
		k.frame = 3 * i;
		k.timestamp = 100.0 + 0.3 * i;
		const bool brk = breakAt > 0 && i >= breakAt;
		k.segment = brk ? 1 : 0;
		k.predicted = brk;
		Eigen::Isometry3d step = Eigen::Isometry3d::Identity();
		if (i > 0)
		{
			step.linear() = Eigen::AngleAxisd(0.03 + 0.02 * U(rng), Eigen::Vector3d::UnitY()).toRotationMatrix();
			step.translation() = Eigen::Vector3d(0.05 * U(rng), 0.01 * U(rng), 2.0 + 0.2 * U(rng));
		}
		k.T_prev_kf = step;
		T_map = T_map * step;
		k.T_map_kf = T_map;
		k.cov_prev_kf = geometry::Matrix6d::Identity() * 1e-4;
		k.cov_prev_kf(0, 5) = k.cov_prev_kf(5, 0) = 1e-6 * i;
		if (brk && i == breakAt) k.cov_prev_kf = geometry::Matrix6d::Identity() * 1e2;
		if (!(mutate == kKfGtMissing && i == 5))
		{
			Eigen::Isometry3d g = T_map;
			g.translation() += Eigen::Vector3d(0.01 * i, 0, 0);
			k.T_gt_kf = g;
		}
		const int target = (mutate == kKfTimestamp || mutate == kKfFrame || mutate == kKfSegment ||
							mutate == kKfPredicted || mutate == kKfPose || mutate == kKfRelPose || mutate == kKfCov ||
							mutate == kKfGtPose) ?
							   7 :
							   -1;
		if (i == target)
		{
			if (mutate == kKfTimestamp) k.timestamp += 1e-6;
			if (mutate == kKfFrame) k.frame += 1;
			if (mutate == kKfPredicted) k.predicted = !k.predicted;
			if (mutate == kKfPose) k.T_map_kf.translation().x() += 1e-9;
			if (mutate == kKfRelPose) k.T_prev_kf.translation().y() += 1e-9;
			if (mutate == kKfCov) k.cov_prev_kf(2, 4) = k.cov_prev_kf(4, 2) = 1e-12;
			if (mutate == kKfGtPose) k.T_gt_kf->translation().z() += 1e-9;
		}
		if (mutate == kKfSegment && i >= 20) k.segment = 2;  // a third segment
		k.channels.resize(2);
		for (int c = 0; c < 2; c++)
			for (int j = 0; j < perKf; j++)
			{
				features::TStereoMeasurement s;
				s.uL = std::floor(10 + 490 * U(rng));
				s.v = std::floor(10 + 360 * U(rng));
				s.uR = s.uL - static_cast<float>(1 + 60 * U(rng));
				s.response = std::floor(10 + 100 * U(rng));
				s.zncc = static_cast<float>(0.8 + 0.2 * U(rng));
				for (auto& w : s.desc.w) w = (uint64_t(rng()) << 32) | rng();
				for (auto& p : s.patch) p = static_cast<uint8_t>(rng());
				const bool here = i == 9 && c == 1 && j == 3;
				if (here && mutate == kMeasUL) s.uL += 1.0f / 16;
				if (here && mutate == kMeasV) s.v += 1.0f / 16;
				if (here && mutate == kMeasUR) s.uR += 1.0f / 16;
				if (here && mutate == kMeasResponse) s.response += 1;
				if (here && mutate == kMeasZncc) s.zncc -= 0.02f;
				if (here && mutate == kMeasDescBit) s.desc.w[2] ^= 1ull << 17;
				if (here && mutate == kMeasPatch) s.patch[40] ^= 4;
				if (here && mutate == kMeasDropped) continue;
				k.channels[c].push_back(s);
			}
		m->appendKeyframe(std::move(k));
	}
	return m;
}

}  // namespace shadyloc::test
