def pytest_addoption(parser):
    parser.addoption("--mcsim", default=None, help="path of the mcsim binary to run")
