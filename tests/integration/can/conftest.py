def pytest_addoption(parser):
    parser.addoption("--mcsim", default=None, help="path of the mcsim binary to run")
    parser.addoption("--pil-image", default=None, help="a firmware image with a CAN model (am263x) for the PIL test")
