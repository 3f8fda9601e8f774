"""touchbench: which classifier recognises a touch best, from recordings to live predictions.

The one import name of the distribution.  Its parts live in the repository's top-level
folders and install as its subpackages:

``touchbench.features``   signal arrays -> feature arrays, event detection, streaming
``touchbench.drivers``    sources of signal blocks: files, bags, sound cards, simulators
``touchbench.benchmark``  data sets, ARFF/CSV, the catalogue, cross-validation, statistics
``touchbench.app``        the store, the services, the CLI, the REST service, the web page

Importing ``touchbench`` itself imports none of them.
"""
