"""What the tests share: data they write, the real service and browser they drive, and
readers of what a command left behind."""
