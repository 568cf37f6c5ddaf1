/* ShadyLoc command line: each subcommand lives in its own cmd_*.cpp and
 * registers itself here, so adding one touches no other file. Each file keeps
 * its code in a namespace named after it (cmd_eval, ...), not an anonymous
 * one: a unity build compiles several files together, and their run() and
 * reg must stay apart. */
#pragma once

#include <functional>
#include <map>
#include <string>
#include <vector>

namespace shadyloc::apps
{
struct Command
{
	std::string summary;  //!< one line for `shadyloc --help`
	/** argv[0] is "shadyloc <name>"; returns the process exit code. */
	std::function<int(int argc, char** argv)> run;
};

std::map<std::string, Command>& commands();

/** Static registration: `static RegisterCommand reg("name", {...});` */
struct RegisterCommand
{
	RegisterCommand(const std::string& name, Command c) { commands()[name] = std::move(c); }
};

}  // namespace shadyloc::apps
