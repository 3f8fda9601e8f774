"""The web page's routes: its pages, and the fragments they load (behind the key)."""
