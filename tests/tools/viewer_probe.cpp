/* What RawLogViewer (MRPT 2.5.8) shows of a file, without a display: a plain
 * MRPT program that knows nothing of ShadyLoc. It loads plugin modules as
 * `RawLogViewer -l` does (mrpt::system::loadPluginModules), reads the file
 * into a CRawlog accepting any CSerializable (the viewer reads the objects
 * itself and inserts each into its CRawlog; loadFromRawLogFile(file, true)
 * reads the same way: other classes become etOther entries, an unknown
 * class ends the read with MRPT's error), then for each entry prints what
 * the viewer's selection shows: the Stringifyable text (the viewer's
 * fallback for objects that are not observations or actions) and, for a
 * Visualizable, the objects getVisualization() puts in its 3D view.
 *   viewer_probe [-l PLUGIN.so[,MORE.so]] FILE
 * Prints "entries: N", then per entry "[i] <type> <class>", its text and
 * "drawing: K objects (...)". Exit 0 when the file was read (even with zero
 * entries, as the viewer reports "Zero entries loaded"), 1 otherwise. */
#include <mrpt/core/Stringifyable.h>
#include <mrpt/obs/CRawlog.h>
#include <mrpt/opengl/CSetOfObjects.h>
#include <mrpt/opengl/Visualizable.h>
#include <mrpt/system/os.h>

#include <iostream>
#include <string>

int main(int argc, char** argv)
{
	std::string plugins, file;
	if (argc == 4 && std::string(argv[1]) == "-l") plugins = argv[2], file = argv[3];
	else if (argc == 2)
		file = argv[1];
	else
	{
		std::cerr << "usage: viewer_probe [-l PLUGIN.so[,MORE.so]] FILE\n";
		return 2;
	}
	// The viewer ignores a plugin that fails to load; the probe does not, so
	// a test cannot pass on a silently missing plugin.
	std::string err;
	if (!plugins.empty() && !mrpt::system::loadPluginModules(plugins, err))
	{
		std::cerr << "cannot load plugin '" << plugins << "': " << err << "\n";
		return 1;
	}
	mrpt::obs::CRawlog rawlog;
	if (!rawlog.loadFromRawLogFile(file, true))
	{
		std::cerr << "cannot open '" << file << "'\n";
		return 1;
	}
	std::cout << "entries: " << rawlog.size() << "\n";
	for (size_t i = 0; i < rawlog.size(); i++)
	{
		static const char* types[] = {"etSensoryFrame", "etActionCollection", "etObservation", "etOther"};
		const auto obj = rawlog.getAsGeneric(i);
		std::cout << "[" << i << "] " << types[rawlog.getType(i)] << " " << obj->GetRuntimeClass()->className << "\n";
		if (const auto* s = dynamic_cast<const mrpt::Stringifyable*>(obj.get())) std::cout << s->asString() << "\n";
		if (const auto v = std::dynamic_pointer_cast<mrpt::opengl::Visualizable>(obj))
		{
			const auto gl = v->getVisualization();
			std::cout << "drawing: " << gl->size() << " objects (";
			const char* sep = "";
			for (const auto& o : *gl) std::cout << sep << o->GetRuntimeClass()->className, sep = ", ";
			std::cout << ")\n";
		}
	}
	return 0;
}
