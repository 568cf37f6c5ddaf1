/* shadyloc — the command line. `shadyloc <command> --help` for each command. */
#include "Command.h"
#include "CommandLine.h"

#include <shadyloc/core/Errors.h>
#include <shadyloc/Registration.h>
#include <shadyloc/io/OutputTransaction.h>


#include <cstring>
#include <string>
#include <iostream>

std::map<std::string, shadyloc::apps::Command>& shadyloc::apps::commands()
{
	static std::map<std::string, Command> all;
	return all;
}

static void usage(std::ostream& o)
{
	o << "ShadyLoc: illumination-invariant stereo localisation on MRPT\n"
		 "(after McManus et al., \"Shady Dealings\", ICRA 2014)\n\n"
		 "usage: shadyloc <command> [options]   (shadyloc <command> --help)\n\ncommands:\n";
	for (const auto& [name, c] : shadyloc::apps::commands())
		o << "  " << name << std::string(name.size() < 12 ? 12 - name.size() : 1, ' ') << c.summary
		  << "\n";
}

int main(int argc, char** argv)
{
	// First, before any thread starts: SIGINT/SIGTERM/SIGHUP/SIGQUIT remove
	// the temporary outputs of the interrupted command.
	shadyloc::io::installSignalCleanup();
	shadyloc::registerAllClasses();
	if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h"))
	{
		usage(argc < 2 ? std::cerr : std::cout);
		return argc < 2 ? 2 : 0;
	}
	if (!std::strcmp(argv[1], "--version"))
	{
		std::cout << "shadyloc " << shadyloc::apps::version() << "\n";
		return 0;
	}
	const std::string name = argv[1];
	auto it = shadyloc::apps::commands().find(name);
	if (it == shadyloc::apps::commands().end())
	{
		std::cerr << "shadyloc: unknown command '" << name << "'\n\n";
		usage(std::cerr);
		return 2;
	}
	std::string argv0 = "shadyloc " + name;
	argv[1] = argv0.data();
	try
	{
		return it->second.run(argc - 1, argv + 1);
	}
	catch (const std::exception& e)
	{
		// what(), not MRPT's exception_to_str: a user wants the reason, not a trace.
		std::cerr << "shadyloc " << name << ": error: " << shadyloc::core::mrptReason(e.what()) << "\n";
		return 1;
	}
}
