"""The shipped DIP and DOG damage models with their model cards, installed as the package
`decoy_cli.models`.

The folder sits at the top of the repository; packaging maps it into the package (setup.py), and
`decoy_cli.package_data.packaged_dir` finds it in a source checkout and in an installed wheel.
"""
