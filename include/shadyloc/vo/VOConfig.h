/* ShadyLoc — the sections of a VO config file (config/vo.ini). */
#pragma once

#include <mrpt/config/CConfigFileBase.h>

#include <memory>
#include <string>
#include <vector>

namespace shadyloc::vo
{
/** Sections a VO config (config/vo.ini, config/vo_sim.ini) may hold, one
 * list for every command that reads such a file (`vo`, `survey`): [vo] and
 * [features] with their per-channel overrides ([vo.mono],
 * [features.invariant], ...), the built-in channels' filter sections [mono]
 * and [invariant], a filter pipeline [filters], and [map] (the keyframe map
 * options the survey reads). */
const std::vector<std::string>& voConfigSections();

/** voConfigSections() plus, for every section of cfg with a `class` key (a
 * channel defined by its filter, filters/Channel.h), that section and its
 * [vo.<name>] / [features.<name>] overrides. */
std::vector<std::string> voConfigSectionsOf(const mrpt::config::CConfigFileBase& cfg);

/** Throws core::SettingsError naming the first section of cfg that is not
 * in voConfigSectionsOf(cfg) (a misspelt [feature] would otherwise be ignored
 * whole), or a key given twice in one section of a file. */
void checkVOConfigSections(const mrpt::config::CConfigFileBase& cfg);

/** The VO config file at `path`, its sections checked (checkVOConfigSections);
 * an empty config (every default) when `path` is empty. Throws
 * std::runtime_error naming a file that does not exist. */
std::unique_ptr<mrpt::config::CConfigFileBase> loadVOConfig(const std::string& path);

}  // namespace shadyloc::vo
