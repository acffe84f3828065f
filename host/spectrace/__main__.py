from spectrace.launch import main

main()
