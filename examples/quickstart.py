# ---
# jupyter:
#   jupytext:
#     formats: py:percent
#     text_representation:
#       extension: .py
#       format_name: percent
#   kernelspec:
#     display_name: Python 3
#     language: python
#     name: python3
# ---

# %% [markdown]
# # touchbench quickstart
#
# From recordings to a trained model in a notebook: simulate a session of touches on a
# robot's three contact microphones, extract one row of features per touch, benchmark
# classifiers (three of touchbench's and a scikit-learn estimator of our own), plot the
# result, train the winner and predict.
#
# Everything is kept in a temporary store for this session; give `store="sqlite:///lab.db"`
# (or a path) to every call to keep it where `touchbench runs` and `touchbench serve` see it.

# %%
import tempfile

from sklearn.linear_model import LogisticRegression
from sklearn.pipeline import make_pipeline
from sklearn.preprocessing import StandardScaler

import touchbench

folder = tempfile.mkdtemp()

# %% [markdown]
# ## Simulate and extract
# Four sessions of taps and strokes, labelled with the gesture and the place touched. Each
# touch becomes one row; the recording it came from is its group.

# %%
recordings, labels = touchbench.simulate(folder, trials=4, touches=10)
touches = touchbench.extract(recordings, labels=labels, extractor="uc3m-audio")
touches[["gesture", "place", "group"]].value_counts().head()

# %% [markdown]
# ## Benchmark
# Leave-one-session-out: each fold tests a session the classifiers never saw.

# %%
own = make_pipeline(StandardScaler(), LogisticRegression(max_iter=500))
board = touchbench.bench(
    touches.attrs["dataset"],
    target="gesture",
    classifiers=["nb", "j48", "ibk", ("scaled-logistic", own)],
    folds="logo",
)
board  # noqa: B018 (a notebook shows its last expression)

# %%
board.to_pandas()[["rank", "mark", "f1_weighted_mean", "f1_weighted_std", "folds"]]

# %%
figure = board.plot("folds")

# %% [markdown]
# ## Train the best and predict
# Models are kept in a format that runs no code, so the catalogue's classifiers are the ones
# trained: the best of them here (`touchbench.train(board)` alone trains the run's winner).

# %%
best = next(c for c in board.to_pandas().index if c != "scaled-logistic")
model = touchbench.train(board, classifier=best)
new_touches = touchbench.extract(
    touchbench.simulate(f"{folder}/new", trials=1, touches=6, seed=7)[0], extractor="uc3m-audio"
)
model.predict(new_touches)

# %%
model.predict_proba(new_touches).round(2)
