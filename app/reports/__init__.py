"""Results rendered for people and other tools: leaderboards as CSV and Markdown, WEKA's
results ARFF, plots and self-contained HTML reports."""
