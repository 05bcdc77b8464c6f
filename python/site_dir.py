"""Prints where a package goes under an installation prefix, relative to it: Debian's python3
looks in PREFIX/lib/python3.X/dist-packages (its default scheme would add another local/),
other interpreters in their posix_prefix platlib (lib/python3.X/site-packages)."""
import os
import sysconfig

version = sysconfig.get_config_var("py_version_short")
if "deb_system" in sysconfig.get_scheme_names():
    print(f"lib/python{version}/dist-packages")
else:
    prefix = "/cwloc-prefix"
    path = sysconfig.get_path("platlib", "posix_prefix", vars={"base": prefix, "platbase": prefix})
    print(os.path.relpath(path, prefix))
