"""Classifiers that compute exactly what WEKA 3.6 computes, on WEKA's encoding.

They take the engine's matrix unchanged (nominal attributes as label codes, NaN for
missing values) with ``nominal_features`` naming the nominal columns, and follow
scikit-learn's estimator contract.  :mod:`benchmark.weka.reference` runs the real WEKA to
check them.
"""

from touchbench.benchmark.weka.c45 import C45Classifier
from touchbench.benchmark.weka.ibk import WekaIBk
from touchbench.benchmark.weka.naive_bayes import WekaNaiveBayes
from touchbench.benchmark.weka.part import PARTClassifier
from touchbench.benchmark.weka.zeror import WekaZeroR

__all__ = ["C45Classifier", "PARTClassifier", "WekaIBk", "WekaNaiveBayes", "WekaZeroR"]
