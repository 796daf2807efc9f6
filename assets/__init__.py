"""The built-in maps' data (one folder per map), installed as the package `decoy_cli.assets`.

The folder sits at the top of the repository; packaging maps it into the package (setup.py), and
`decoy_cli.package_data.packaged_dir` finds it in a source checkout and in an installed wheel.
"""
