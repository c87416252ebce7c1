from shoal.app.cli import entry

entry()
