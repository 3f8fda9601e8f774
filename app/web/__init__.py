"""The web page served at ``/``: server-rendered HTML (Jinja2) and one small script, no
build step, nothing fetched from elsewhere."""
