from robosoc.cli import main

main()
