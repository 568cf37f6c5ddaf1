/* ShadyLoc — the sections of a VO config file (config/vo.ini). */
#pragma once

#include <mrpt/config/CConfigFileBase.h>

#include <string>
#include <vector>

namespace shadyloc::vo
{
/** Sections a VO config may hold: [vo] and [features] with their per-channel
 * overrides ([vo.mono], [features.invariant], ...), and [invariant]. */
const std::vector<std::string>& voConfigSections();

/** Throws core::SettingsError naming the first section of cfg that the VO
 * does not read (a misspelt [feature] would otherwise be ignored whole). */
void checkVOConfigSections(const mrpt::config::CConfigFileBase& cfg);

}  // namespace shadyloc::vo
