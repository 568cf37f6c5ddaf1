/* shadyloc — the command line. `shadyloc <command> --help` for each command. */
#include "Command.h"
#include "CommandLine.h"

#include <shadyloc/core/Registration.h>
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

/** The reason, without MRPT's call-stack dump: MRPT exceptions carry
 * "Message: <why>" (nested ones several) between "Location:" lines and
 * backtraces; the innermost message says what went wrong. */
static std::string userMessage(const std::string& what)
{
	const auto pos = what.rfind("Message:");
	if (what.find("==== MRPT exception ====") == std::string::npos || pos == std::string::npos) return what;
	std::string msg = what.substr(pos + 8);
	for (const char* stop : {"\nLocation:", "\nCall stack", "\n===="})
		if (const auto e = msg.find(stop); e != std::string::npos) msg = msg.substr(0, e);
	const auto b = msg.find_first_not_of(" \t\n");
	const auto e = msg.find_last_not_of(" \t\n");
	return b == std::string::npos ? what : msg.substr(b, e - b + 1);
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
		std::cerr << "shadyloc " << name << ": error: " << userMessage(e.what()) << "\n";
		return 1;
	}
}
