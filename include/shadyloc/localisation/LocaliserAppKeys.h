/* ShadyLoc — the keys of the public LocaliserOptions' own section, declared
 * once (core/Options.h). Here, not in Localiser.h, which includes only MRPT
 * and std headers (and no area may include it). */
#pragma once

#include <shadyloc/core/Options.h>

#include <string>

namespace shadyloc::localisation
{
/** LocaliserOptions' sensor_label and start_keyframe, as an options struct
 * (src/localisation/Localiser.cpp). */
struct TLocaliserAppKeys
{
	std::string& sensor_label;
	int& start_keyframe;

	void keys(core::KeyVisitor& v);
	void validate() const { core::checkKeys(*this); }
};

}  // namespace shadyloc::localisation
