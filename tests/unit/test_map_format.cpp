/* Tests of the keyframe map's persistence: byte-exact round trips, every
 * field reaching the bytes, the map inside a CMultiMetricMap made from .ini
 * text, a file opened by another process through the plugin only, damaged
 * files, and saves killed part-way. */
#include <shadyloc/filters/Filters.h>
#include <shadyloc/map/CKeyframeMap.h>

#include "../support/TestSupport.h"
#include "test_map_support.h"

#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/io/CFileOutputStream.h>
#include <mrpt/io/CMemoryStream.h>
#include <mrpt/maps/CMultiMetricMap.h>
#include <mrpt/serialization/CArchive.h>

#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <regex>

using namespace shadyloc;
namespace fs = std::filesystem;

namespace
{
std::vector<uint8_t> bytesOf(const mrpt::serialization::CSerializable& o)
{
	mrpt::io::CMemoryStream mem;
	auto ar = mrpt::serialization::archiveFrom(mem);
	ar << o;
	const auto* p = static_cast<const uint8_t*>(mem.getRawBufferData());
	return std::vector<uint8_t>(p, p + mem.getTotalBytesCount());
}
void writeFirstBytes(const std::string& path, const std::vector<uint8_t>& b, size_t n)
{
	std::ofstream f(path, std::ios::binary | std::ios::trunc);
	f.write(reinterpret_cast<const char*>(b.data()), static_cast<std::streamsize>(n));
}
}  // namespace

TEST(MapFormat, RoundTripIsByteIdenticalAndLossless)
{
	const auto m = test::makeSyntheticMap();
	const std::string dir = test::tempDir("map_roundtrip"), a = dir + "/a.kfmap", b = dir + "/b.kfmap";
	m->saveToFile(a);
	const auto loaded = CKeyframeMap::LoadFromFile(a);
	loaded->saveToFile(b);
	EXPECT_EQ(test::fileBytes(a), test::fileBytes(b));
	EXPECT_EQ(bytesOf(*m), bytesOf(*loaded));
	// Field by field: the in-memory map is what the file holds (quantised on insertion).
	ASSERT_EQ(loaded->keyframeCount(), m->keyframeCount());
	EXPECT_TRUE(loaded->options == m->options);
	EXPECT_EQ(loaded->runs(), m->runs());
	ASSERT_EQ(loaded->channels().size(), 2u);
	EXPECT_TRUE(loaded->channels()[1] == m->channels()[1]);
	for (uint32_t i = 0; i < m->keyframeCount(); i++)
	{
		const auto &x = m->keyframe(i), &y = loaded->keyframe(i);
		EXPECT_EQ(x.timestamp, y.timestamp);
		EXPECT_EQ(x.segment, y.segment);
		EXPECT_EQ(x.predicted, y.predicted);
		EXPECT_TRUE(x.T_map_kf.isApprox(y.T_map_kf, 0));
		EXPECT_EQ(x.cov_prev_kf, y.cov_prev_kf);
		ASSERT_EQ(bool(x.T_gt_kf), bool(y.T_gt_kf));
		for (size_t c = 0; c < 2; c++)
		{
			ASSERT_EQ(x.channels[c].size(), y.channels[c].size());
			for (size_t j = 0; j < x.channels[c].size(); j++)
			{
				const auto &p = x.channels[c][j], &q = y.channels[c][j];
				EXPECT_EQ(p.uL, q.uL);
				EXPECT_EQ(p.uR, q.uR);
				EXPECT_EQ(p.desc, q.desc);
				EXPECT_EQ(p.patch, q.patch);
				EXPECT_EQ(p.P, q.P);
				EXPECT_EQ(p.cov, q.cov);
			}
		}
	}
	// Quantisation to 1/16 px loses at most half a quantum.
	EXPECT_GT(m->keyframe(3).channels[0][0].P.z(), 0);
	EXPECT_NEAR(m->chainDistance(10), loaded->chainDistance(10), 0);
}

TEST(MapFormat, FewerPatchBitsRoundTripAndStoreLess)
{
	// patch_bits = 6: every patch pixel is held as the middle of its 4-level
	// step (within 2 grey levels of the original), in memory as in the file.
	const auto m8 = test::makeSyntheticMap(), m6 = test::makeSyntheticMap(24, 40, 15, test::kOptPatchBits);
	ASSERT_EQ(m6->options.patch_bits, 6);
	const auto b6 = bytesOf(*m6);
	const auto back = CKeyframeMap::LoadFromBytes(b6.data(), b6.size());
	EXPECT_EQ(bytesOf(*back), b6);
	int worst = 0;
	for (uint32_t i = 0; i < m8->keyframeCount(); i++)
		for (size_t c = 0; c < 2; c++)
			for (size_t j = 0; j < m8->keyframe(i).channels[c].size(); j++)
			{
				const auto &a = m8->keyframe(i).channels[c][j].patch, &b = m6->keyframe(i).channels[c][j].patch,
						   &l = back->keyframe(i).channels[c][j].patch;
				EXPECT_EQ(b, l);
				for (size_t k = 0; k < a.size(); k++)
				{
					worst = std::max(worst, std::abs(int(a[k]) - int(b[k])));
					EXPECT_EQ(b[k] % 4, 2) << "not the middle of its step";
				}
			}
	EXPECT_LE(worst, 2);
	// Two bits fewer of 81 patch bytes per measurement: the channel blocks shrink.
	const auto s8 = m8->sizeReport(), s6 = m6->sizeReport();
	for (size_t c = 0; c < 2; c++) EXPECT_LT(s6.channel_bytes[c], s8.channel_bytes[c]) << "channel " << c;
}

TEST(MapFormat, EveryFieldReachesTheBytes)
{
	const auto ref = bytesOf(*test::makeSyntheticMap());
	for (int k = 1; k < test::kMutationCount; k++)
	{
		const auto other = bytesOf(*test::makeSyntheticMap(24, 40, 15, k));
		EXPECT_NE(ref, other) << "mutation " << k << " did not change the stored bytes";
	}
	// And the baseline is deterministic (the comparison above can fail only by a field).
	EXPECT_EQ(ref, bytesOf(*test::makeSyntheticMap()));
}

TEST(MapFormat, InsideACMultiMetricMapFromIni)
{
	const std::string ini =
		"[map]\n"
		"keyframeMap_count = 1\n"
		"pointsMap_count = 1\n"
		"[map_keyframeMap_00_creationOpts]\n"
		"kf_spacing_m = 2.5\n"
		"landmarks_per_keyframe = 90\n"
		"compression_level = 5\n";
	mrpt::config::CConfigFileMemory cfg(ini);
	mrpt::maps::TSetOfMetricMapInitializers init;
	init.loadFromConfigFile(cfg, "map");
	mrpt::maps::CMultiMetricMap mm;
	mm.setListOfMaps(init);
	auto km = mm.mapByClass<CKeyframeMap>();
	ASSERT_TRUE(km) << "CMultiMetricMap did not create a shadyloc::CKeyframeMap from the .ini";
	EXPECT_EQ(km->options.kf_spacing_m, 2.5);
	EXPECT_EQ(km->options.landmarks_per_keyframe, 90);
	EXPECT_EQ(km->options.compression_level, 5);
	EXPECT_TRUE(km->isEmpty());
	// Filled, serialised as part of the multi-map, and read back whole.
	auto filled = test::makeSyntheticMap();
	filled->options = km->options;
	*km = *filled;
	const auto bytes = bytesOf(mm);
	mrpt::io::CMemoryStream mem;
	mem.assignMemoryNotOwn(bytes.data(), bytes.size());
	auto back = mrpt::serialization::archiveFrom(mem).ReadObject<mrpt::maps::CMultiMetricMap>();
	ASSERT_TRUE(back);
	auto km2 = back->mapByClass<CKeyframeMap>();
	ASSERT_TRUE(km2);
	EXPECT_EQ(bytesOf(*km2), bytesOf(*filled));
	EXPECT_EQ(km2->keyframeCount(), 24u);
	// A bad option is an error naming the section.
	mrpt::config::CConfigFileMemory bad(
		"[m]\nkeyframeMap_count = 1\n[m_keyframeMap_00_creationOpts]\nkf_spacing_deg = -3\n");
	mrpt::maps::TSetOfMetricMapInitializers init2;
	try
	{
		init2.loadFromConfigFile(bad, "m");
		FAIL() << "a negative kf_spacing_deg was accepted";
	}
	catch (const std::exception& e)
	{
		EXPECT_NE(std::string(e.what()).find("m_keyframeMap_00_creationOpts"), std::string::npos) << e.what();
		EXPECT_NE(std::string(e.what()).find("kf_spacing_deg"), std::string::npos) << e.what();
	}
}

TEST(MapFormat, OpenedByAnotherProcessWithOnlyThePlugin)
{
	const std::string dir = test::tempDir("map_plugin"), path = dir + "/m.kfmap";
	test::makeSyntheticMap()->saveToFile(path);
	std::string out;
	ASSERT_EQ(test::runCommand(std::string(SHADYLOC_KFMAP_LOADER) + " " + test::pluginPath() + " " + path, &out), 0)
		<< out;
	EXPECT_NE(out.find("class: shadyloc::CKeyframeMap"), std::string::npos) << out;
	EXPECT_NE(out.find("24 keyframes"), std::string::npos) << out;
	// Without the plugin the same program must fail (the class is unknown), not print a map.
	EXPECT_NE(test::runCommand(std::string(SHADYLOC_KFMAP_LOADER) + " /nonexistent/plugin.so " + path, &out), 0);
	// MRPT's own rawlog-edit reads it as a one-object file with the plugin.
	if (test::runCommand("command -v rawlog-edit >/dev/null") == 0)
	{
		ASSERT_EQ(test::runCommand("rawlog-edit -p " + test::pluginPath() + " -i " + path + " --info", &out), 0) << out;
		EXPECT_TRUE(std::regex_search(out, std::regex("number of objects\\s*:\\s*1\\b"))) << out;
		EXPECT_EQ(out.find("not registered"), std::string::npos) << out;
		// Without the plugin MRPT cannot read the object (the check above can fail).
		test::runCommand("rawlog-edit -i " + path + " --info", &out);
		EXPECT_NE(out.find("'shadyloc::CKeyframeMap' which is not registered"), std::string::npos) << out;
	}
}

TEST(MapFormat, DamagedFilesAreCleanErrors)
{
	const std::string dir = test::tempDir("map_bad"), path = dir + "/bad.kfmap";
	const auto good = bytesOf(*test::makeSyntheticMap(6, 8, 4));
	const size_t n = good.size();
	auto expectError = [&](const std::string& what) {
		try
		{
			CKeyframeMap::LoadFromFile(path);
			ADD_FAILURE() << what << ": loaded without an error";
		}
		catch (const std::runtime_error& e)
		{
			EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << what << ": " << e.what();
		}
	};
	// Offsets: every one of the first 160 bytes (class header, block sizes and
	// sums, the first frame's header), then 600 spread over the rest. (Each
	// failed load costs a few ms: MRPT's exceptions carry a stack trace.)
	std::vector<size_t> offsets;
	for (size_t k = 0; k < std::min<size_t>(160, n); k++) offsets.push_back(k);
	for (size_t i = 0; i < 600; i++) offsets.push_back(160 + i * (n - 160) / 600);
	offsets.push_back(n - 1);
	for (size_t k : offsets)
	{
		writeFirstBytes(path, good, k);
		expectError("truncated at " + std::to_string(k));
	}
	int flips = 0;
	for (size_t k : offsets)
		for (uint8_t x : {0x01, 0x80, 0xff})
		{
			if (k >= 160 && x != 0x01) continue;
			auto b = good;
			b[k] ^= x;
			writeFirstBytes(path, b, n);
			expectError("byte " + std::to_string(k) + " ^ " + std::to_string(x));
			flips++;
		}
	EXPECT_GE(flips, 1000);
	// A version this build does not know: the byte after the class name.
	{
		const std::string name = "shadyloc::CKeyframeMap";
		auto it = std::search(good.begin(), good.end(), name.begin(), name.end());
		ASSERT_NE(it, good.end());
		auto b = good;
		b[(it - good.begin()) + name.size()] = 7;
		writeFirstBytes(path, b, n);
		try
		{
			CKeyframeMap::LoadFromFile(path);
			ADD_FAILURE() << "version 7 loaded";
		}
		catch (const std::runtime_error& e)
		{
			EXPECT_NE(std::string(e.what()).find("version"), std::string::npos) << e.what();
		}
	}
	// Empty, and a serialised object of another class.
	writeFirstBytes(path, good, 0);
	expectError("empty");
	{
		mrpt::io::CFileOutputStream f(path);
		auto ar = mrpt::serialization::archiveFrom(f);
		ar << CFilterMonochrome();
	}
	expectError("another class");
	// Trailing garbage after a whole map.
	{
		auto b = good;
		b.push_back(0);
		writeFirstBytes(path, b, b.size());
		expectError("trailing byte");
	}
	EXPECT_THROW(CKeyframeMap::LoadFromFile(dir + "/missing.kfmap"), std::runtime_error);
}

namespace
{
uint64_t fnv1a(const std::vector<uint8_t>& b)
{
	uint64_t h = 0xcbf29ce484222325ull;
	for (uint8_t x : b) h = (h ^ x) * 0x100000001b3ull;
	return h;
}
}  // namespace

TEST(MapFormat, OldVersionAndLyingBlockSizesAreRefused)
{
	const std::string dir = test::tempDir("map_lying"), path = dir + "/m.kfmap";
	const auto good = bytesOf(*test::makeSyntheticMap(6, 8, 4));
	const std::string name = "shadyloc::CKeyframeMap";
	const size_t ver = 1 + name.size();	 // MRPT's header: 0x80 | length, the name, the version
	ASSERT_EQ(std::string(good.begin() + 1, good.begin() + 1 + name.size()), name);
	ASSERT_EQ(good[ver], 6);
	// The loader on bytes in memory (the fuzz entry point) loads them as the file loader does.
	EXPECT_EQ(CKeyframeMap::LoadFromBytes(good.data(), good.size())->keyframeCount(), 6u);
	try
	{
		CKeyframeMap::LoadFromBytes(good.data(), 100, "first 100 bytes");
		ADD_FAILURE() << "a truncated map loaded from memory";
	}
	catch (const std::runtime_error& e)
	{
		EXPECT_NE(std::string(e.what()).find("first 100 bytes"), std::string::npos) << e.what();
	}
	// Version 0 (channels as kinds, before channels were filters): refused, saying what to do.
	{
		auto b = good;
		b[ver] = 0;
		writeFirstBytes(path, b, b.size());
		try
		{
			CKeyframeMap::LoadFromFile(path);
			ADD_FAILURE() << "version 0 loaded";
		}
		catch (const std::runtime_error& e)
		{
			EXPECT_NE(std::string(e.what()).find("rebuild the map"), std::string::npos) << e.what();
		}
	}
	// Block 0 rewritten to claim 48 GiB of content, consistently: the stored
	// raw size, the zstd frame's content size field and the checksum all
	// agree. Only the data is short. The loader must refuse it without
	// allocating what the header claims (a zero-filled 48 GiB buffer would
	// end this process).
	const size_t blk = ver + 1 + 1;	 // after the block count
	auto u64at = [&](const std::vector<uint8_t>& b, size_t at) {
		uint64_t v;
		std::memcpy(&v, b.data() + at, 8);
		return v;
	};
	const uint64_t compSize = u64at(good, blk + 8);
	const size_t frame = blk + 24;
	std::vector<uint8_t> comp(good.begin() + frame, good.begin() + frame + compSize);
	ASSERT_EQ(comp[0], 0x28);  // zstd magic, little-endian 0xFD2FB528
	const uint8_t fhd = comp[4];
	const bool single = (fhd >> 5) & 1;
	const int fcsFlag = fhd >> 6, didFlag = fhd & 3;
	const size_t fcsBytes[] = {single ? 1u : 0u, 2, 4, 8};
	const size_t didBytes[] = {0, 1, 2, 4};
	const size_t fcsAt = 5 + (single ? 0 : 1) + didBytes[didFlag];
	const uint64_t claimed = 48ull << 30;
	std::vector<uint8_t> lying(comp.begin(), comp.begin() + fcsAt);
	lying[4] = static_cast<uint8_t>((fhd & 0x3f) | (3 << 6));	 // 8-byte content size field
	for (int i = 0; i < 8; i++) lying.push_back(static_cast<uint8_t>(claimed >> (8 * i)));
	lying.insert(lying.end(), comp.begin() + fcsAt + fcsBytes[fcsFlag], comp.end());
	std::vector<uint8_t> b(good.begin(), good.begin() + blk);
	auto put64 = [&](uint64_t v) {
		for (int i = 0; i < 8; i++) b.push_back(static_cast<uint8_t>(v >> (8 * i)));
	};
	put64(claimed);
	put64(lying.size());
	put64(fnv1a(lying));
	b.insert(b.end(), lying.begin(), lying.end());
	b.insert(b.end(), good.begin() + frame + compSize, good.end());
	writeFirstBytes(path, b, b.size());
	try
	{
		CKeyframeMap::LoadFromFile(path);
		ADD_FAILURE() << "a block claiming 48 GiB loaded";
	}
	catch (const std::runtime_error& e)
	{
		const std::string w = e.what();
		EXPECT_NE(w.find(path), std::string::npos) << w;
		EXPECT_NE(w.find("block 0"), std::string::npos) << w;
	}
}

TEST(MapFormat, Version1MapsStillLoad)
{
	// tests/golden/CKeyframeMap_v1.bin: the format-test map (test_formats.cpp,
	// populatedKeyframeMap) as version 1 wrote it, before the options held
	// the landmark selection. It loads; its selection reads as the strongest
	// corners (the only one then), the rest as stored; saved again it is a
	// map of the current version that loads to the same content.
	const auto v1 = test::fileBytes(std::string(SHADYLOC_SOURCE_DIR) + "/tests/golden/CKeyframeMap_v1.bin");
	const std::string name = "shadyloc::CKeyframeMap";
	ASSERT_GT(v1.size(), 2 + name.size());
	ASSERT_EQ(v1[1 + name.size()], 1) << "the fixture is not a version 1 map";
	const auto m = CKeyframeMap::LoadFromBytes(v1.data(), v1.size(), "CKeyframeMap_v1.bin");
	EXPECT_EQ(m->options.landmark_selection, TKeyframeMapOptions::LandmarkSelection::Strongest);
	EXPECT_EQ(m->options.landmarks_per_keyframe, 77);
	EXPECT_EQ(m->options.kf_spacing_m, 2.25);
	EXPECT_EQ(m->options.reobservation_window_m, TKeyframeMapOptions().reobservation_window_m);
	EXPECT_EQ(m->options.patch_bits, 8);
	EXPECT_EQ(m->keyframeCount(), 3u);
	ASSERT_EQ(m->channels().size(), 2u);
	EXPECT_EQ(m->channels()[1].label, "inv9");
	EXPECT_EQ(m->runs(), (std::vector<std::string>{"dawn", "dusk"}));
	EXPECT_EQ(m->keyframe(2).channels[1].size(), 3u);
	const auto now = bytesOf(*m);
	EXPECT_EQ(now[1 + name.size()], 6);
	const auto back = CKeyframeMap::LoadFromBytes(now.data(), now.size());
	EXPECT_TRUE(back->options == m->options);
	EXPECT_EQ(bytesOf(*back), now);
}

// tests/golden/CKeyframeMap_v2.bin: the format-test map as version 2 wrote it
// (checksums of the bytes alone). It loads, to the content the current
// golden file (version 6) holds.
TEST(MapFormat, Version2MapsStillLoad)
{
	const std::string golden = std::string(SHADYLOC_SOURCE_DIR) + "/tests/golden/";
	const auto v2 = test::fileBytes(golden + "CKeyframeMap_v2.bin"), now = test::fileBytes(golden + "CKeyframeMap.bin");
	const std::string name = "shadyloc::CKeyframeMap";
	ASSERT_GT(v2.size(), 2 + name.size());
	ASSERT_EQ(v2[1 + name.size()], 2) << "the fixture is not a version 2 map";
	ASSERT_EQ(now[1 + name.size()], 6);
	const auto m = CKeyframeMap::LoadFromBytes(v2.data(), v2.size(), "CKeyframeMap_v2.bin");
	EXPECT_EQ(bytesOf(*m), now);
}

// tests/golden/CKeyframeMap_v3.bin: the format-test map as version 3 wrote
// it, before channels recorded their descriptor kind and landmarks their
// normals. It loads with every channel FAST + BRIEF and no normals, to the
// content the current golden file holds.
TEST(MapFormat, Version3MapsStillLoadAsBrief)
{
	const std::string golden = std::string(SHADYLOC_SOURCE_DIR) + "/tests/golden/";
	const auto v3 = test::fileBytes(golden + "CKeyframeMap_v3.bin"), now = test::fileBytes(golden + "CKeyframeMap.bin");
	const std::string name = "shadyloc::CKeyframeMap";
	ASSERT_GT(v3.size(), 2 + name.size());
	ASSERT_EQ(v3[1 + name.size()], 3) << "the fixture is not a version 3 map";
	const auto m = CKeyframeMap::LoadFromBytes(v3.data(), v3.size(), "CKeyframeMap_v3.bin");
	for (const auto& c : m->channels()) EXPECT_EQ(c.descriptor, features::DescriptorKind::Brief) << c.label;
	// ... and without surface normals (its landmarks are matched unwarped).
	for (const auto& k : m->keyframes())
		for (const auto& ch : k.channels)
			for (const auto& meas : ch) EXPECT_TRUE(meas.normal.isZero());
	EXPECT_EQ(bytesOf(*m), now);
}

// tests/golden/CKeyframeMap_v4.bin: the format-test map as version 4 wrote
// it, before maps held several experiences. It loads as one anchored
// experience per run, without links, to the content the current golden
// file holds.
TEST(MapFormat, Version4MapsLoadAsAnchoredRunsWithoutLinks)
{
	const std::string golden = std::string(SHADYLOC_SOURCE_DIR) + "/tests/golden/";
	const auto v4 = test::fileBytes(golden + "CKeyframeMap_v4.bin"), now = test::fileBytes(golden + "CKeyframeMap.bin");
	const std::string name = "shadyloc::CKeyframeMap";
	ASSERT_GT(v4.size(), 2 + name.size());
	ASSERT_EQ(v4[1 + name.size()], 4) << "the fixture is not a version 4 map";
	const auto m = CKeyframeMap::LoadFromBytes(v4.data(), v4.size(), "CKeyframeMap_v4.bin");
	ASSERT_GE(m->runs().size(), 2u);
	for (uint16_t r = 0; r < m->runs().size(); r++) EXPECT_TRUE(m->runAnchored(r));
	EXPECT_TRUE(m->links().empty());
	EXPECT_EQ(bytesOf(*m), now);
}

// tests/golden/CKeyframeMap_v5.bin: the format-test map as version 5 wrote
// it, before landmark depths were refined by re-observations. It loads with
// every depth the pair's (no disparity sigma), to the content the current
// golden file holds.
TEST(MapFormat, Version5MapsLoadWithThePairsDepths)
{
	const std::string golden = std::string(SHADYLOC_SOURCE_DIR) + "/tests/golden/";
	const auto v5 = test::fileBytes(golden + "CKeyframeMap_v5.bin"), now = test::fileBytes(golden + "CKeyframeMap.bin");
	const std::string name = "shadyloc::CKeyframeMap";
	ASSERT_GT(v5.size(), 2 + name.size());
	ASSERT_EQ(v5[1 + name.size()], 5) << "the fixture is not a version 5 map";
	const auto m = CKeyframeMap::LoadFromBytes(v5.data(), v5.size(), "CKeyframeMap_v5.bin");
	EXPECT_FALSE(m->options.depth_from_reobservations);
	for (const auto& k : m->keyframes())
		for (const auto& ch : k.channels)
			for (const auto& meas : ch) EXPECT_EQ(meas.sigma_d, 0.f);
	EXPECT_EQ(bytesOf(*m), now);
}

// Version 6 stores a refined disparity's sigma per landmark (1/128 px, rounded
// up, with the disparity's own rounding to 1/16 px added): it comes back as
// stored, the landmark's covariance follows it (the depth's variance
// shrinks with it), and the map saves to the same bytes.
TEST(MapFormat, RefinedDisparitySigmaRoundTrips)
{
	auto m = test::makeSyntheticMap(3, 4, 0);
	auto kf = m->keyframe(0);
	kf.id = 0;
	const double qd2 = 1.0 / (16.0 * 16.0 * 12.0);
	std::vector<double> set;
	for (size_t j = 0; j < kf.channels[0].size(); j++)
	{
		kf.channels[0][j].sigma_d = j == 0 ? 0.f : static_cast<float>(0.01 + 0.05 * j);
		set.push_back(kf.channels[0][j].sigma_d);
	}
	auto refined = CKeyframeMap::Create();
	refined->options = m->options;
	refined->setup(m->calibration(), m->imageWidth(), m->imageHeight(), m->channels());
	for (const auto& r : m->runs()) refined->addRun(r);
	refined->appendKeyframe(kf);
	const auto& stored = refined->keyframe(0).channels[0];
	ASSERT_EQ(stored.size(), set.size());
	for (size_t j = 0; j < stored.size(); j++)
	{
		if (set[j] == 0)
		{
			EXPECT_EQ(stored[j].sigma_d, 0.f);
			continue;
		}
		// Rounded up to 1/128 px; the covariance adds the disparity's rounding.
		EXPECT_GE(stored[j].sigma_d, set[j] - 1e-6);
		EXPECT_LT(stored[j].sigma_d, set[j] + 1.0 / 128);
		Eigen::Matrix3d J;
		Eigen::Vector3d P;
		ASSERT_TRUE(m->calibration().triangulate(stored[j].uL, stored[j].v, stored[j].uR, P, &J));
		const double sd = std::sqrt(double(stored[j].sigma_d) * stored[j].sigma_d + qd2);
		EXPECT_TRUE(stored[j].cov.isApprox(
			m->calibration().triangulationCovariance(J, m->channels()[0].sigma_px, sd), 1e-9));
		EXPECT_LT(stored[j].cov(2, 2), m->keyframe(0).channels[0][j].cov(2, 2));
	}
	const auto b = bytesOf(*refined);
	const auto back = CKeyframeMap::LoadFromBytes(b.data(), b.size());
	for (size_t j = 0; j < stored.size(); j++)
	{
		EXPECT_EQ(back->keyframe(0).channels[0][j].sigma_d, stored[j].sigma_d);
		EXPECT_TRUE(back->keyframe(0).channels[0][j].cov.isApprox(stored[j].cov, 1e-6));
	}
	EXPECT_EQ(bytesOf(*back), b);
	// Appending a stored keyframe again (an experience copied into another
	// map) keeps its sigmas as they are.
	auto again = CKeyframeMap::Create();
	again->options = m->options;
	again->setup(m->calibration(), m->imageWidth(), m->imageHeight(), m->channels());
	for (const auto& r : m->runs()) again->addRun(r);
	again->appendKeyframe(back->keyframe(0));
	for (size_t j = 0; j < stored.size(); j++) EXPECT_EQ(again->keyframe(0).channels[0][j].sigma_d, stored[j].sigma_d);
}

TEST(MapFormat, DescriptorKindRoundTrips)
{
	// An ORB channel with its pyramid comes back as such (version 4).
	const auto m = test::makeSyntheticMap(4, 3, 0, test::kChannelDescriptor);
	auto b = bytesOf(*m);
	auto back = CKeyframeMap::LoadFromBytes(b.data(), b.size());
	EXPECT_EQ(back->channels()[1].descriptor, features::DescriptorKind::Orb);
	EXPECT_TRUE(back->channels()[1] == m->channels()[1]);
	const auto s = test::makeSyntheticMap(4, 3, 0, test::kChannelOrbScale);
	b = bytesOf(*s);
	back = CKeyframeMap::LoadFromBytes(b.data(), b.size());
	EXPECT_EQ(back->channels()[1].orb_scale_factor, 1.3);
}

// Version 4 stores a surface normal per landmark (3 x int8): a map built
// with normals loads them back as they were stored (unit length up to the
// quantisation, unknown ones zero), and saves to the same bytes.
TEST(MapFormat, SurfaceNormalsRoundTrip)
{
	auto m = test::makeSyntheticMap(4, 10, 4);
	CKeyframeMap withNormals;
	withNormals.options = m->options;
	withNormals.setup(m->calibration(), m->imageWidth(), m->imageHeight(), m->channels());
	for (const auto& r : m->runs()) withNormals.addRun(r);
	size_t i = 0;
	for (auto k : m->keyframes())
	{
		for (auto& ch : k.channels)
			for (auto& meas : ch)
				meas.normal = i++ % 3 == 0 ? Eigen::Vector3f::Zero()
										   : Eigen::Vector3f(0.3f * std::sin(0.7f * i), -1.f, -0.2f * std::cos(0.3f * i)).normalized();
		withNormals.appendKeyframe(k);
	}
	const auto bytes = bytesOf(withNormals);
	const auto back = CKeyframeMap::LoadFromBytes(bytes.data(), bytes.size());
	size_t known = 0;
	for (uint32_t k = 0; k < back->keyframeCount(); k++)
		for (size_t c = 0; c < back->channels().size(); c++)
		{
			const auto& a = withNormals.keyframe(k).channels[c];
			const auto& b = back->keyframe(k).channels[c];
			ASSERT_EQ(a.size(), b.size());
			for (size_t j = 0; j < a.size(); j++)
			{
				EXPECT_EQ(a[j].normal, b[j].normal);  // quantised once, when appended
				if (b[j].normal.isZero()) continue;
				known++;
				EXPECT_NEAR(b[j].normal.norm(), 1.0f, 0.02f);	// 3 x int8: unit up to rounding
			}
		}
	EXPECT_GT(known, 0u);
	EXPECT_EQ(bytesOf(*back), bytes);
}

namespace
{
/** Offsets of the blocks of a saved map: [start of the block's header, end of its data). */
std::vector<std::pair<size_t, size_t>> blockSpans(const std::vector<uint8_t>& b)
{
	const size_t ver = 1 + std::string("shadyloc::CKeyframeMap").size();
	std::vector<std::pair<size_t, size_t>> spans;
	size_t at = ver + 2;  // the version byte, the block count
	for (int i = 0; i < b[ver + 1]; i++)
	{
		uint64_t comp;
		std::memcpy(&comp, b.data() + at + 8, 8);
		spans.emplace_back(at, at + 24 + comp);
		at += 24 + comp;
	}
	return spans;
}
}  // namespace

// Each block's checksum covered its bytes only: the two channels' blocks
// swapped (headers and all) loaded, each channel with the other's
// measurements. The sum now covers the block's position.
TEST(MapFormat, SwappedChannelBlocksAreRefused)
{
	const auto good = bytesOf(*test::makeSyntheticMap(6, 8, 4));
	const auto spans = blockSpans(good);
	ASSERT_EQ(spans.size(), 3u);  // metadata, mono, invariant
	ASSERT_EQ(spans.back().second + 1, good.size());  // then MRPT's end-of-object byte
	std::vector<uint8_t> b(good.begin(), good.begin() + spans[1].first);
	b.insert(b.end(), good.begin() + spans[2].first, good.begin() + spans[2].second);
	b.insert(b.end(), good.begin() + spans[1].first, good.begin() + spans[1].second);
	b.push_back(good.back());
	ASSERT_EQ(b.size(), good.size());
	ASSERT_NE(b, good);
	try
	{
		CKeyframeMap::LoadFromBytes(b.data(), b.size(), "swapped.kfmap");
		ADD_FAILURE() << "a map with its channel blocks swapped loaded";
	}
	catch (const std::runtime_error& e)
	{
		const std::string w = e.what();
		EXPECT_NE(w.find("swapped.kfmap"), std::string::npos) << w;
		EXPECT_NE(w.find("block 1: checksum mismatch"), std::string::npos) << w;
	}
}

// The loader read the whole file before looking at its header: `map-info
// /dev/zero` grew until bad_alloc, naming nothing. Now a file that is not
// regular is refused unread, and the header is checked before the rest.
TEST(MapFormat, NonRegularFilesAndForeignFilesAreRefusedUnread)
{
	const std::string dir = test::tempDir("map_not_regular");
	ASSERT_EQ(::mkfifo((dir + "/fifo.kfmap").c_str(), 0600), 0);
	for (const std::string& path : {std::string("/dev/zero"), dir, dir + "/fifo.kfmap"})
	{
		try
		{
			CKeyframeMap::LoadFromFile(path);
			ADD_FAILURE() << path << " loaded";
		}
		catch (const std::runtime_error& e)
		{
			EXPECT_NE(std::string(e.what()).find("'" + path + "': not a regular file"), std::string::npos) << e.what();
		}
	}
	// A large file of zeros: its first byte is no MRPT object header.
	{
		std::ofstream(dir + "/zeros.kfmap");
		fs::resize_file(dir + "/zeros.kfmap", 64 << 20);
		try
		{
			CKeyframeMap::LoadFromFile(dir + "/zeros.kfmap");
			ADD_FAILURE() << "zeros loaded";
		}
		catch (const std::runtime_error& e)
		{
			EXPECT_NE(std::string(e.what()).find("zeros.kfmap': holds no MRPT object"), std::string::npos) << e.what();
		}
	}
	// The program, with its memory capped in case the loader regresses.
	std::string out;
	EXPECT_NE(test::runCommand("ulimit -v 4000000; timeout 60 " + test::appPath() + " map-info /dev/zero", &out), 0)
		<< out;
	EXPECT_NE(out.find("'/dev/zero': not a regular file"), std::string::npos) << out;
}

TEST(MapFormat, KilledSavesLeaveThePreviousFileLoadable)
{
	const std::string dir = test::tempDir("map_atomic"), path = dir + "/m.kfmap";
	// Old map on disk; the new one is large enough for many 64 kB chunks.
	const auto oldMap = test::makeSyntheticMap(6, 20, 0);
	oldMap->saveToFile(path);
	const auto oldBytes = test::fileBytes(path);
	const auto newMap = test::makeSyntheticMap(60, 150, 40);
	const size_t total = bytesOf(*newMap).size();
	const size_t chunks = (total + (64 << 10) - 1) / (64 << 10);
	ASSERT_GE(chunks, 20u) << "the test map must span at least 20 chunks";
	std::printf("[map-atomic] %zu bytes, %zu chunks: %zu kill points\n", total, chunks, chunks + 1);
	int killedAt = 0;
	for (size_t c = 0; c <= chunks; c++)
	{
		const pid_t pid = fork();
		ASSERT_GE(pid, 0);
		if (pid == 0)
		{
			// Child: killed after c chunks (c = 0: before the first byte lands;
			// c = chunks: the temporary file is complete, not yet renamed).
			size_t seen = 0;
			if (c == 0) raise(SIGKILL);
			newMap->saveToFile(path, [&](size_t) {
				if (++seen == c) raise(SIGKILL);
			});
			_exit(3);
		}
		int status = 0;
		waitpid(pid, &status, 0);
		ASSERT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL) << "chunk " << c;
		killedAt++;
		EXPECT_EQ(test::fileBytes(path), oldBytes) << "killed after chunk " << c;
		EXPECT_NO_THROW(CKeyframeMap::LoadFromFile(path)) << "killed after chunk " << c;
	}
	EXPECT_GE(killedAt, 20);
	// An uninterrupted save replaces it.
	newMap->saveToFile(path);
	EXPECT_EQ(CKeyframeMap::LoadFromFile(path)->keyframeCount(), 60u);
}
