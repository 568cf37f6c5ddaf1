/* ShadyLoc — keyframe map types: channel parameters. */
#include <shadyloc/map/MapTypes.h>

#include <cmath>
#include <map>
#include <set>
#include <sstream>
#include <vector>

namespace shadyloc::map
{
TChannelParams TChannelParams::From(
	const std::string& label, const std::string& filterClass, const std::string& filterOptions,
	const features::TStereoFeatureOptions& fo)
{
	TChannelParams p;
	p.label = label;
	p.filter_class = filterClass;
	p.filter_options = filterOptions;
	p.brief_patch_size = fo.brief_patch_size;
	p.brief_seed = fo.brief_seed;
	p.presmooth_sigma = fo.presmooth_sigma;
	p.descriptor = fo.descriptor;
	p.orb_levels = fo.orb_levels;
	p.orb_scale_factor = fo.orb_scale_factor;
	p.sigma_px = fo.sigma_px;
	return p;
}

namespace
{
/** "key = value" lines as key -> value (blank lines and comments skipped). */
std::map<std::string, std::string> optionLines(const std::string& text)
{
	std::map<std::string, std::string> kv;
	std::istringstream in(text);
	std::string line;
	auto trim = [](std::string x) {
		const auto a = x.find_first_not_of(" \t\r"), b = x.find_last_not_of(" \t\r");
		return a == std::string::npos ? std::string() : x.substr(a, b - a + 1);
	};
	while (std::getline(in, line))
	{
		line = trim(line);
		if (line.empty() || line[0] == ';' || line[0] == '#') continue;
		const auto eq = line.find('=');
		if (eq == std::string::npos)
			kv[line] = "";
		else
			kv[trim(line.substr(0, eq))] = trim(line.substr(eq + 1));
	}
	return kv;
}
}  // namespace

std::string TChannelParams::filterOptionsLine() const
{
	std::string out;
	for (const auto& [k, v] : optionLines(filter_options)) out += (out.empty() ? "" : " ") + k + "=" + v;
	return out;
}

std::string TChannelParams::asString() const
{
	std::ostringstream s;
	s << "'" << label << "': " << filter_class;
	const std::string o = filterOptionsLine();
	if (!o.empty()) s << " (" << o << ")";
	if (descriptor == features::DescriptorKind::Orb)
		s << ", ORB " << orb_levels << " levels scale " << orb_scale_factor;
	else
		s << ", BRIEF patch " << brief_patch_size << " px seed " << brief_seed;
	s << ", presmooth " << presmooth_sigma << " px";
	return s.str();
}

std::string TChannelParams::differences(const TChannelParams& o) const
{
	std::vector<std::string> d;
	if (filter_class != o.filter_class) d.push_back("filter class");
	const auto a = optionLines(filter_options), b = optionLines(o.filter_options);
	std::set<std::string> keys;
	for (const auto& kv : a) keys.insert(kv.first);
	for (const auto& kv : b) keys.insert(kv.first);
	for (const auto& k : keys)
	{
		const auto ia = a.find(k), ib = b.find(k);
		if (ia == a.end() || ib == b.end() || ia->second != ib->second) d.push_back("filter option " + k);
	}
	// BRIEF's pattern shapes BRIEF descriptors only, ORB's pyramid ORB's only.
	using features::DescriptorKind;
	if (descriptor != o.descriptor)
		d.push_back(std::string("descriptor: map ") + features::toString(descriptor) + ", live " + features::toString(o.descriptor));
	else if (descriptor == DescriptorKind::Brief)
	{
		if (brief_patch_size != o.brief_patch_size) d.push_back("BRIEF patch size");
		if (brief_seed != o.brief_seed) d.push_back("BRIEF pattern seed");
	}
	else
	{
		if (orb_levels != o.orb_levels) d.push_back("ORB pyramid levels");
		if (std::abs(orb_scale_factor - o.orb_scale_factor) > 1e-9) d.push_back("ORB scale factor");
	}
	if (std::abs(presmooth_sigma - o.presmooth_sigma) > 1e-9) d.push_back("pre-smoothing");
	std::string out;
	for (const auto& x : d) out += (out.empty() ? "" : ", ") + x;
	return out;
}

bool TChannelParams::operator==(const TChannelParams& o) const
{
	return label == o.label && filter_class == o.filter_class && filter_options == o.filter_options &&
		   brief_patch_size == o.brief_patch_size && brief_seed == o.brief_seed &&
		   presmooth_sigma == o.presmooth_sigma && descriptor == o.descriptor && orb_levels == o.orb_levels &&
		   orb_scale_factor == o.orb_scale_factor && sigma_px == o.sigma_px;
}

}  // namespace shadyloc::map
