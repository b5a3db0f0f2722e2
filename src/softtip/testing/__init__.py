"""Tools for tests: a fake Net F/T sensor."""
